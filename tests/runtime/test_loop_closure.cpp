// Loop closure (runtime/loop_closure.hpp) and the mapper's submaps: a robot drives two laps of
// a loop in the simulated lab while its pose estimate drifts (0.3 deg and 3 cm per metre); the
// loop closer must find the start area again, move the map and the pose back near the truth
// (without it the error grows to ~0.6 m), and its rebuilt grid must agree with the world better
// than the drifted one. Plus the mapper's submap bookkeeping and the settings' errors.
#include <duet/kernels/error.hpp>
#include <duet/runtime/localization/loop_closure.hpp>
#include <duet/runtime/mapping/mapper.hpp>
#include <duet/runtime/config/profile.hpp>
#include <duet/runtime/robot/robot_io.hpp>
#include <duet/sim/renderer.hpp>
#include <duet/sim/sim_explore.hpp>
#include <duet/sim/world.hpp>

#include <gtest/gtest.h>

#include "sanitized.hpp"

#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <optional>
#include <vector>

namespace duet {
namespace test_loop_closure {

constexpr float kDeg = std::numbers::pi_v<float> / 180.0f;

/// Two and a half laps of a 2.75 m x 3.55 m rectangle in the lab's middle (free of furniture), in
/// steps of at most 0.3 m and turns of at most 30 deg at the corners; with the path length.
struct Step {
  Pose2 truth;
  float s = 0.0f;
};
std::vector<Step> loop_path() {
  const std::vector<Eigen::Vector2f> corners{{4.0f, 2.1f}, {6.75f, 2.1f}, {6.75f, 5.65f}, {4.0f, 5.65f}};
  std::vector<Step> out;
  float s = 0.0f;
  float heading = 0.0f;
  for (int leg = 0; leg < 10; ++leg) {
    const Eigen::Vector2f a = corners[static_cast<std::size_t>(leg % 4)], b = corners[static_cast<std::size_t>((leg + 1) % 4)];
    const float target = std::atan2(b.y() - a.y(), b.x() - a.x());
    // Turn in place.
    const float turn = std::remainder(target - heading, 2.0f * std::numbers::pi_v<float>);
    const int nt = static_cast<int>(std::ceil(std::fabs(turn) / (30.0f * kDeg)));
    for (int k = 1; k <= nt; ++k) out.push_back({{a.x(), a.y(), heading + turn * static_cast<float>(k) / static_cast<float>(nt)}, s});
    heading = target;
    const float len = (b - a).norm();
    const int n = static_cast<int>(std::ceil(len / 0.3f));
    for (int k = 1; k <= n; ++k) {
      const Eigen::Vector2f p = a + (b - a) * (static_cast<float>(k) / static_cast<float>(n));
      s += len / static_cast<float>(n);
      out.push_back({{p.x(), p.y(), heading}, s});
    }
  }
  return out;
}

/// The drift of the estimate after s metres: estimate = drift(s) * truth (scale 0: a pose that is right).
Pose2 drift(float s, float scale = 1.0f) { return Pose2{scale * 0.03f * s, 0.0f, scale * 0.3f * kDeg * s}; }

struct DriveResult {
  std::vector<float> errors;      // |estimate - truth| after each step's update [m]
  std::size_t closures = 0;
  float max_shift_m = 0.0f;
  std::size_t rejected_unexplained = 0;
  std::size_t occupied_on_walls = 0, occupied = 0;  // grid cells occupied, and of those near a true obstacle
};

DriveResult drive(bool loop_closure, float drift_scale = 1.0f, float min_prediction_conflict = LoopClosureSettings{}.min_prediction_conflict,
                  float prediction_check_min_shift_m = LoopClosureSettings{}.prediction_check_min_shift_m) {
  const Profile profile = builtin_profile("dual");
  const sim::World world = sim::builtin_world("lab");
  const sim::RgbdRenderer renderer(world);
  Mapper mapper(profile.mapping);
  LoopClosureSettings ls;
  ls.submap_duration_s = 8.0;
  ls.min_age_s = 15.0;
  ls.check_period_s = 2.0;
  ls.query_window_s = 6.0;
  ls.min_prediction_conflict = min_prediction_conflict;
  ls.prediction_check_min_shift_m = prediction_check_min_shift_m;
  std::optional<LoopCloser> lc;
  if (loop_closure) lc.emplace(ls, profile.exploration.cells, mapper);
  std::vector<RgbdImage> images(profile.sensors.size());
  Pose2 shift{};
  DriveResult run;
  double t = 0.0;
  for (const Step& st : loop_path()) {
    t += 1.0;
    std::vector<SensorFrame> frames;
    for (std::size_t i = 0; i < profile.sensors.size(); ++i) {
      const SensorProfile& sp = profile.sensors[i];
      renderer.render(sp, to_isometry(st.truth) * sp.T_robot_optical(), static_cast<std::uint64_t>(t * 10 + static_cast<double>(i)), images[i]);
      frames.push_back(frame_view(images[i], sp, sp.T_robot_optical()));
    }
    const Pose2 at = compose(shift, compose(drift(st.s, drift_scale), st.truth));
    mapper.integrate(frames, to_isometry(at));
    if (lc) {
      if (const auto d = lc->update(mapper, at, t)) shift = compose(*d, shift);
    }
    const Pose2 est = compose(shift, compose(drift(st.s, drift_scale), st.truth));
    run.errors.push_back(std::hypot(est.x - st.truth.x, est.y - st.truth.y));
  }
  if (lc) {
    run.closures = lc->stats().closures;
    run.max_shift_m = lc->stats().max_shift_m;
    run.rejected_unexplained = lc->stats().rejected_unexplained;
  }
  // The grid against the world: occupied cells within 0.15 m of a true obstacle's footprint.
  const OccupancyGrid& g = mapper.grid();
  for (int y = 0; y < g.height(); ++y)
    for (int x = 0; x < g.width(); ++x) {
      if (classify(g.at(x, y), profile.exploration.cells) != CellState::kOccupied) continue;
      ++run.occupied;
      const Eigen::Vector2f c = g.cell_center(x, y);
      run.occupied_on_walls += sim::clearance(world, c, 0.0f, 2.0f) <= 0.15f;
    }
  return run;
}

TEST(LoopClosure, ADriftedLoopIsClosedAndTheMapFollows) {
  const DriveResult without = drive(false);
  const DriveResult with = drive(true);
  ASSERT_EQ(with.errors.size(), without.errors.size());
  std::printf("steps %zu; end error: without %.3f m, with %.3f m (%zu closures); occupied on obstacles: %zu/%zu vs %zu/%zu\n",
              with.errors.size(), static_cast<double>(without.errors.back()), static_cast<double>(with.errors.back()), with.closures,
              with.occupied_on_walls, with.occupied, without.occupied_on_walls, without.occupied);
  // Without loop closure the error is the drift: > 0.6 m at the end.
  EXPECT_GT(without.errors.back(), 0.6f);
  EXPECT_EQ(without.closures, 0u);
  EXPECT_GE(with.closures, 1u);
  // With it the pose comes back near the truth: the end error is a fraction of the drift (the
  // drift since the last closure remains).
  EXPECT_LT(with.errors.back(), 0.4f * without.errors.back());
  float worst_second_half = 0.0f;
  for (std::size_t k = with.errors.size() / 2; k < with.errors.size(); ++k) worst_second_half = std::max(worst_second_half, with.errors[k]);
  EXPECT_LT(worst_second_half, 0.5f * without.errors.back());
  // The map: more of its occupied cells lie on true obstacles.
  ASSERT_GT(with.occupied, 100u);
  const double frac_with = static_cast<double>(with.occupied_on_walls) / static_cast<double>(with.occupied);
  const double frac_without = static_cast<double>(without.occupied_on_walls) / static_cast<double>(without.occupied);
  EXPECT_GT(frac_with, frac_without + 0.05) << frac_with << " vs " << frac_without;
}

TEST(LoopClosure, ASmallDriftIsClosedWithoutThePredictionCheck) {
  // A quarter of the drift above: after a lap the pose is ~0.1 m / 1 deg off, so a wall's points
  // lie within verify_hit_m and a cell of the old wall and the old map cannot contradict the
  // prediction. The check has no power there: below prediction_check_min_shift_m it is not
  // applied (freiburg-101 seed 1 had ten such 0.10-0.13 m corrections of a pose 0.8 m off turned
  // down). A share no match can reach (1.0) makes the gate visible: with it the small drift is
  // still closed; with the gate at 0 every correction is checked and turned down.
  const DriveResult gated = drive(true, 0.25f, 1.0f);
  EXPECT_GE(gated.closures, 1u);
  EXPECT_LT(gated.max_shift_m, LoopClosureSettings{}.prediction_check_min_shift_m + 0.05f);
  if (duet_test::short_runs()) return;  // sanitized builds: the gated run only
  const DriveResult checked = drive(true, 0.25f, 1.0f, 0.0f);
  std::printf("small drift, every share too low: gate %.2f m: %zu closures (max shift %.3f m, %zu turned down), end error %.3f m; "
              "gate 0: %zu closures, %zu turned down, end error %.3f m\n",
              static_cast<double>(LoopClosureSettings{}.prediction_check_min_shift_m), gated.closures,
              static_cast<double>(gated.max_shift_m), gated.rejected_unexplained, static_cast<double>(gated.errors.back()),
              checked.closures, checked.rejected_unexplained, static_cast<double>(checked.errors.back()));
  EXPECT_EQ(checked.closures, 0u);
  EXPECT_GE(checked.rejected_unexplained, 1u);
  EXPECT_LT(gated.errors.back(), checked.errors.back());
}

TEST(LoopClosure, AnAliasDoesNotMoveAPoseTheOldMapDoesNotContradict) {
  // The lab, the single-sensor robot, seed 3, frontier goals that end when seen, the paper's test
  // of R_g with eps_R 1 bit (the defaults until stop 45): at 236 s, with
  // the pose 0.05 m from the truth, a wide match laid the new walls 0.9 m along an aisle on the
  // old ones (score 0.78, confirmed, chi2 within its gate) and the pose went 0.92 m off. At the
  // predicted pose the query's points lay on old walls or unseen cells, none on old free floor:
  // min_prediction_conflict turns such a match down. Without the check the scene must still
  // show the alias (so it tests the check); the genuine closures of
  // ADriftedLoopIsClosedAndTheMapFollows pass it.
  const bool short_run = duet_test::short_runs();
  for (const bool checked : {false, true}) {
    if (short_run && !checked) continue;  // sanitized builds: the checked run only
    Profile profile = builtin_profile("single");
    profile.exploration.strategy.eps_r_unknown_only = false;  // the paper's eps_R test and value: the run that met the alias
    profile.exploration.strategy.eps_r_bits = 1.0f;
    sim::ExploreSettings es;
    es.seed = 3;
    es.max_time_s = 250.0;
    es.runtime = profile.runtime;
    es.runtime.explorer.frontier_seen_radius_m = 0.3f;
    // The heading-rate gains of the run that met the alias (the profile's until stop 50).
    es.runtime.pose_correction.rate_gain_initial = PoseCorrectionSettings{}.rate_gain_initial;
    es.runtime.pose_correction.rate_gain = PoseCorrectionSettings{}.rate_gain;
    if (!checked) es.runtime.loop_closure.min_prediction_conflict = 0.0f;
    sim::SimExplore run(sim::builtin_world("lab"), profile, es);
    run.run();
    const sim::ExploreSummary s = run.summary();
    std::printf("check %s: pose error max %.3f m, closures %zu (max shift %.3f m), rejected as unexplained %zu, collisions %zu\n",
                checked ? "on" : "off", s.pose_error_max_m, s.loops.closures, static_cast<double>(s.loops.max_shift_m),
                s.loops.rejected_unexplained, s.collisions);
    if (!checked) {
      EXPECT_GT(s.pose_error_max_m, 0.5) << "the scene no longer shows the alias: it does not test the check";
      continue;
    }
    EXPECT_LT(s.pose_error_max_m, 0.25);
    EXPECT_LT(s.loops.max_shift_m, 0.25f);
    EXPECT_GE(s.loops.rejected_unexplained, 1u);
    EXPECT_EQ(s.collisions, 0u);
    // Each match's record says what the check saw: the turned-down ones would have moved the map
    // on a share below the threshold, the others did not need it or had it.
    const LoopCloser* lc = run.runtime().loop_closer();
    ASSERT_NE(lc, nullptr);
    const float gate = es.runtime.loop_closure.min_prediction_conflict;
    const float min_shift = es.runtime.loop_closure.prediction_check_min_shift_m;
    std::size_t turned_down = 0, unchecked_small = 0;
    for (const LoopMatchRecord& m : lc->matches()) {
      EXPECT_GE(m.prediction_conflict, 0.0f);
      EXPECT_LE(m.prediction_conflict, 1.0f);
      // The mean shift of the query's points is at least what the translation alone would give
      // minus a turn's share, and never negative.
      EXPECT_GE(m.shift_m, 0.0f);
      EXPECT_EQ(m.accepted, !(m.moves_map && m.shift_m >= min_shift && m.prediction_conflict < gate)) << "at " << m.t_s << " s";
      turned_down += !m.accepted;
      unchecked_small += m.moves_map && m.shift_m < min_shift && m.prediction_conflict < gate;
      if (!m.accepted) {
        EXPECT_GE(m.shift_m, min_shift);
      }
    }
    EXPECT_EQ(turned_down, s.loops.rejected_unexplained);
    std::printf("matches %zu: turned down %zu, small shifts let through unchecked %zu\n", lc->matches().size(), turned_down,
                unchecked_small);
  }
}

TEST(Mapper, SubmapsHoldTheirObservationsAndMoveTheGrid) {
  const Profile profile = builtin_profile("dual");
  const sim::World world = sim::builtin_world("lab");
  const sim::RgbdRenderer renderer(world);
  Mapper mapper(profile.mapping);
  EXPECT_THROW((void)mapper.open_submap(), Error);
  mapper.keep_submaps();
  ASSERT_EQ(mapper.submaps().size(), 1u);
  EXPECT_EQ(mapper.open_submap(), 0u);  // an empty open submap is reused
  std::vector<RgbdImage> images(profile.sensors.size());
  auto integrate = [&](const Pose2& p) {
    std::vector<SensorFrame> frames;
    for (std::size_t i = 0; i < profile.sensors.size(); ++i) {
      const SensorProfile& sp = profile.sensors[i];
      renderer.render(sp, to_isometry(p) * sp.T_robot_optical(), 1, images[i]);
      frames.push_back(frame_view(images[i], sp, sp.T_robot_optical()));
    }
    mapper.integrate(frames, to_isometry(p));
  };
  integrate({4.0f, 2.1f, 0.0f});
  EXPECT_EQ(mapper.open_submap(), 1u);
  integrate({6.75f, 4.0f, 1.6f});
  ASSERT_EQ(mapper.submaps().size(), 2u);
  EXPECT_EQ(mapper.submaps()[0].frames, profile.sensors.size());
  EXPECT_GT(mapper.submaps()[1].grid.known_cells(), 100u);
  EXPECT_THROW(mapper.keep_submaps(), Error);
  const std::size_t cloud_points = mapper.cloud().size();
  EXPECT_GT(cloud_points, 1000u);
  // Identity placements: the grid is the clamped sum of the submaps (same observed cells).
  const std::size_t known = mapper.grid().known_cells();
  const std::vector<Pose2> identity(2);
  mapper.place_submaps(identity);
  EXPECT_EQ(mapper.grid().known_cells(), known);
  // Moving the second submap by 1 m moves its cells: a cell only it saw is now 1 m further.
  const OccupancyGrid& s1 = mapper.submaps()[1].grid;
  const OccupancyGrid& s0 = mapper.submaps()[0].grid;
  std::optional<Eigen::Vector2f> only1;
  for (int y = 0; y < s1.height() && !only1; ++y)
    for (int x = 0; x < s1.width() && !only1; ++x) {
      if (classify(s1.at(x, y), profile.exploration.cells) != CellState::kOccupied) continue;
      const Eigen::Vector2f c = s1.cell_center(x, y);
      bool seen0 = false;
      for (float dx = -1.5f; dx <= 1.51f && !seen0; dx += 0.05f) {
        const Eigen::Vector2i k = s0.cell_of(c + Eigen::Vector2f(dx, 0.0f));
        seen0 = s0.in_bounds(k.x(), k.y()) && !std::isnan(s0.at(k.x(), k.y()));
      }
      if (!seen0) only1 = c;
    }
  ASSERT_TRUE(only1.has_value());
  const std::vector<Pose2> moved{Pose2{}, Pose2{1.0f, 0.0f, 0.0f}};
  mapper.place_submaps(moved);
  const Eigen::Vector2i at_new = mapper.grid().cell_of(*only1 + Eigen::Vector2f(1.0f, 0.0f));
  const Eigen::Vector2i at_old = mapper.grid().cell_of(*only1);
  EXPECT_EQ(classify(mapper.grid().at(at_new.x(), at_new.y()), profile.exploration.cells), CellState::kOccupied);
  EXPECT_TRUE(!mapper.grid().in_bounds(at_old.x(), at_old.y()) || std::isnan(mapper.grid().at(at_old.x(), at_old.y())));
  EXPECT_EQ(mapper.submaps()[1].placement.x, 1.0f);
  // The cloud moves with it (re-filtered: about the same size).
  const PointCloud& moved_cloud = mapper.cloud();
  EXPECT_NEAR(static_cast<double>(moved_cloud.size()), static_cast<double>(cloud_points), 0.2 * static_cast<double>(cloud_points));
  // Bad placements.
  EXPECT_THROW(mapper.place_submaps(std::vector<Pose2>(3)), Error);
  EXPECT_THROW(mapper.place_submaps(std::vector<Pose2>{Pose2{}, Pose2{std::nanf(""), 0.0f, 0.0f}}), Error);
  EXPECT_EQ(mapper.submaps()[1].placement.x, 1.0f);
}

// A finished map (LoopCloser::freeze(), when exploration ends): no submap opens and no loop
// search runs however long the robot goes on, while the mapper still takes the observations.
TEST(LoopClosure, FrozenMapOpensNoSubmapAndSearchesNoLoop) {
  const Profile profile = builtin_profile("dual");
  const sim::World world = sim::builtin_world("lab");
  const sim::RgbdRenderer renderer(world);
  Mapper mapper(profile.mapping);
  LoopClosureSettings ls;
  ls.submap_duration_s = 4.0;
  ls.min_age_s = 8.0;
  ls.check_period_s = 1.0;
  LoopCloser lc(ls, profile.exploration.cells, mapper);
  std::vector<RgbdImage> images(profile.sensors.size());
  // The loop's first 20 steps (~5 m) open five submaps and check for loops; frozen, the robot
  // drives them back (the same area: the grid takes the observations without growing).
  std::vector<Step> path = loop_path();
  path.resize(20);
  for (std::size_t j = 20; j-- > 0;) path.push_back(path[j]);
  auto step = [&](std::size_t k, double t) {
    std::vector<SensorFrame> frames;
    for (std::size_t i = 0; i < profile.sensors.size(); ++i) {
      const SensorProfile& sp = profile.sensors[i];
      renderer.render(sp, to_isometry(path[k].truth) * sp.T_robot_optical(), k * 10 + i, images[i]);
      frames.push_back(frame_view(images[i], sp, sp.T_robot_optical()));
    }
    mapper.integrate(frames, to_isometry(path[k].truth));
    (void)lc.update(mapper, path[k].truth, t);
  };
  std::size_t k = 0;
  for (; k < path.size() / 2; ++k) step(k, static_cast<double>(k));
  const std::size_t submaps = mapper.submaps().size();
  const std::size_t checks = lc.stats().checks;
  ASSERT_GE(submaps, 3u);
  ASSERT_GT(checks, 0u);
  EXPECT_FALSE(lc.frozen());
  EXPECT_EQ(lc.stats().frozen_at_s, -1.0);
  lc.freeze(static_cast<double>(k));
  lc.freeze(static_cast<double>(k) + 5.0);  // idempotent: the first time is kept
  mapper.freeze_cloud();
  mapper.freeze_cloud();
  EXPECT_TRUE(mapper.cloud_frozen());
  const std::size_t open_cloud = mapper.submaps().back().cloud.size();
  const std::size_t cloud = mapper.cloud().size();
  const OccupancyGrid grid_before = mapper.grid();
  EXPECT_TRUE(lc.frozen());
  EXPECT_EQ(lc.stats().frozen_at_s, static_cast<double>(k));
  const std::size_t frames_before = mapper.submaps().back().frames;
  for (; k < path.size(); ++k) step(k, static_cast<double>(k));
  EXPECT_EQ(mapper.submaps().size(), submaps);
  EXPECT_EQ(lc.stats().checks, checks);
  EXPECT_EQ(lc.stats().closures, 0u);
  // The open submap took every later observation into its grid; the cloud stayed as it was.
  EXPECT_EQ(mapper.submaps().back().frames, frames_before + (path.size() - path.size() / 2) * profile.sensors.size());
  EXPECT_EQ(mapper.submaps().back().cloud.size(), open_cloud);
  EXPECT_EQ(mapper.cloud().size(), cloud);
  const OccupancyGrid& after = mapper.grid();
  std::size_t changed = 0;
  if (after.width() == grid_before.width() && after.height() == grid_before.height()) {
    for (std::size_t i = 0; i < after.logodds().size(); ++i) {
      const float a = after.logodds()[i], b = grid_before.logodds()[i];
      changed += !((std::isnan(a) && std::isnan(b)) || a == b);
    }
  } else {
    changed = 1;  // the grid grew
  }
  EXPECT_GT(changed, 100u) << "the grid keeps taking observations";
}

TEST(LoopClosure, BadSettingsAreNamed) {
  auto expect_bad = [](LoopClosureSettings s, const char* field) {
    try {
      validate(s);
      ADD_FAILURE() << "no error for " << field;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
    }
  };
  LoopClosureSettings s;
  EXPECT_NO_THROW(validate(s));
  s.submap_duration_s = 0.0;
  expect_bad(s, "submap_duration_s");
  s = {};
  s.check_period_s = -1.0;
  expect_bad(s, "check_period_s");
  s = {};
  s.verify_free_m = 0.01f;
  expect_bad(s, "verify_free_m");
  s = {};
  s.loop_sigma_xy_m = 0.0f;
  expect_bad(s, "loop_sigma_xy_m");
  s = {};
  s.min_prediction_conflict = 1.5f;
  expect_bad(s, "min_prediction_conflict");
  s.min_prediction_conflict = std::numeric_limits<float>::quiet_NaN();
  expect_bad(s, "min_prediction_conflict");
  s = {};
  s.prediction_check_min_shift_m = -0.1f;
  expect_bad(s, "prediction_check_min_shift_m");
  s.prediction_check_min_shift_m = std::numeric_limits<float>::infinity();
  expect_bad(s, "prediction_check_min_shift_m");
  s = {};
  s.match.min_score = 2.0f;
  expect_bad(s, "min_score");
  s = {};
  s.graph.max_iterations = 0;
  expect_bad(s, "max_iterations");
  // A loop closer needs a fresh mapper.
  const Profile profile = builtin_profile("dual");
  Mapper mapper(profile.mapping);
  LoopCloser lc({}, profile.exploration.cells, mapper);
  EXPECT_TRUE(mapper.keeps_submaps());
  Mapper other(profile.mapping);
  EXPECT_THROW((void)lc.update(other, Pose2{}, 0.0), Error);
  EXPECT_THROW((void)lc.update(mapper, Pose2{std::nanf(""), 0.0f, 0.0f}, 0.0), Error);
}

}  // namespace test_loop_closure
}  // namespace duet
