// PoseCorrector::confirm_odometry: a robot carried 0.6 m while its odometry stood still is
// relocalised by the wide re-match - unless the odometry is confirmed (vision tracking well, no
// visual jump gated out), when the wide re-match is not tried and the hold is counted. And the
// runtime: a kidnapped robot with vision fused is still relocalised (its first view after the
// move is a visual jump the gate rejects, so vision does not confirm the wheels then, and the
// jump asks for the wide re-match at once: contradict_odometry).
#include <duet/kernels/error.hpp>
#include <duet/kernels/scan_match.hpp>
#include <duet/runtime/config/profile.hpp>
#include <duet/runtime/localization/pose_corrector.hpp>
#include <duet/runtime/mapping/mapper.hpp>
#include <duet/runtime/robot/robot_io.hpp>
#include <duet/sim/renderer.hpp>
#include <duet/sim/sim_explore.hpp>
#include <duet/sim/world.hpp>

#include <gtest/gtest.h>

#include "sanitized.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <initializer_list>
#include <limits>
#include <vector>

namespace duet {
namespace test_pose_corrector_hold {

struct Kidnap {
  std::size_t relocalizations = 0, held = 0, asked = 0, ambiguous = 0, in_obstacle = 0;
  float truth_clearance_m = 0.0f;  ///< the carried robot's true place: distance to the map's nearest occupied cell
  float error_m = 0.0f;  ///< of the last pose the corrector returned, against the truth
  int first_at = -1;     ///< the update after the carry that relocalised first (-1: none)
  RelocalizationScores scores;  ///< of the last relocalisation
  Pose2 offset;                 ///< the carry: the truth's offset from the odometry (map frame)
  std::size_t at_edge = 0;      ///< wide re-matches not taken: on the window's edge
};

/// Every sensor's frame at the robot pose `truth` (frame noise seeded seed + sensor index), viewing
/// `images` (one per sensor).
std::vector<SensorFrame> render_frames(const sim::RgbdRenderer& renderer, const Profile& profile, const Pose2& truth, std::uint64_t seed,
                                       std::vector<RgbdImage>& images) {
  std::vector<SensorFrame> frames;
  for (std::size_t i = 0; i < profile.sensors.size(); ++i) {
    const SensorProfile& sp = profile.sensors[i];
    renderer.render(sp, to_isometry(truth) * sp.T_robot_optical(), seed + i, images[i]);
    frames.push_back(frame_view(images[i], sp, sp.T_robot_optical()));
  }
  return frames;
}

/// `confirmed`: confirm_odometry(true) from the carry on; `contradicted`: contradict_odometry()
/// before the first update after it (vision gated out the jump).
/// The dual profile's pose correction, the settings the kidnap runs with unless given others.
PoseCorrectionSettings dual_settings() { return builtin_profile("dual").runtime.pose_correction; }

Kidnap kidnap(bool confirmed, bool contradicted = false, const PoseCorrectionSettings& settings = dual_settings()) {
  Profile profile = builtin_profile("dual");
  profile.runtime.pose_correction = settings;
  const sim::World world = sim::builtin_world("lab");
  const sim::RgbdRenderer renderer(world);
  Mapper mapper(profile.mapping);
  PoseCorrector corrector(profile, profile.runtime.pose_correction);
  std::vector<RgbdImage> images(profile.sensors.size());
  auto frames_at = [&](const Pose2& truth, std::uint64_t seed) { return render_frames(renderer, profile, truth, seed, images); };
  // A turn in place at the start maps the room around it (odometry = truth).
  Pose2 truth = world.start;
  double t = 0.0;
  for (int k = 0; k < 26; ++k, t += 0.5) {
    truth.theta = std::remainder(truth.theta + 0.25f, 2.0f * 3.14159265f);
    const auto frames = frames_at(truth, 10 + 2 * static_cast<std::uint64_t>(k));
    mapper.integrate(frames, to_isometry(corrector.update(frames, truth, mapper.grid(), t)));
  }
  // Carried 0.6 m sideways; the odometry does not see it.
  const Pose2 odom = truth;
  truth.x += 0.6f * std::cos(truth.theta + 1.5708f);
  truth.y += 0.6f * std::sin(truth.theta + 1.5708f);
  corrector.confirm_odometry(confirmed);
  if (contradicted) corrector.contradict_odometry();
  Pose2 at;
  int first_at = -1;
  for (int k = 0; k < 6; ++k, t += 0.5) {
    const auto frames = frames_at(truth, 100 + 2 * static_cast<std::uint64_t>(k));
    at = corrector.update(frames, odom, mapper.grid(), t);  // not integrated: the map stays right
    if (first_at < 0 && corrector.relocalizations() > 0) first_at = k;
  }
  InflatedGrid distance;
  occupied_distance(GridView(mapper.grid()), profile.exploration.cells, distance);
  const Eigen::Vector2i tc = distance.cell_of(Eigen::Vector2f(truth.x, truth.y));
  Kidnap r{corrector.relocalizations(), corrector.relocalizations_held(), corrector.relocalizations_asked(),
           corrector.relocalizations_ambiguous(), corrector.relocalizations_in_obstacle(), distance.clearance_m[distance.index(tc.x(), tc.y())]};
  r.at_edge = corrector.relocalizations_at_edge();
  r.offset = Pose2{truth.x - odom.x, truth.y - odom.y, 0.0f};
  r.error_m = std::hypot(at.x - truth.x, at.y - truth.y);
  r.first_at = first_at;
  r.scores = corrector.last_relocalization_scores();
  return r;
}

/// Each of `values` in `field` (the rest the defaults) fails validate().
void expect_rejected(float PoseCorrectionSettings::*field, std::initializer_list<float> values) {
  for (const float v : values) {
    PoseCorrectionSettings bad;
    bad.*field = v;
    EXPECT_THROW(validate(bad), Error) << v;
  }
}

/// A wide re-match turned down by one check: not taken, counted in `counter`, the pose left with
/// the odometry; and `off`, the same carry with that check off: relocalised, nothing counted.
void expect_refused_by(std::size_t Kidnap::*counter, const Kidnap& refused, const Kidnap& off) {
  EXPECT_EQ(refused.relocalizations, 0u);
  EXPECT_GE(refused.*counter, 1u);
  EXPECT_GT(refused.error_m, 0.3f) << "the pose stays with the odometry";
  EXPECT_GE(off.relocalizations, 1u);
  EXPECT_EQ(off.*counter, 0u);
}

TEST(PoseCorrectorHold, AConfirmedOdometryHoldsTheWideRematch) {
  const Kidnap free = kidnap(false);
  std::printf("carried 0.6 m: relocalised at a score of %.2f (prediction %.2f, best other fit %.2f)\n", free.scores.score, free.scores.prior,
              free.scores.runner_up);
  EXPECT_GE(free.relocalizations, 1u);
  EXPECT_EQ(free.held, 0u);
  EXPECT_LT(free.error_m, 0.15f) << "relocalised";
  const Kidnap held = kidnap(true);
  EXPECT_EQ(held.relocalizations, 0u);
  EXPECT_GE(held.held, 1u);
  EXPECT_GT(held.error_m, 0.3f) << "the pose stays with the confirmed odometry";
}

// The wide re-match's runner-up: the carried robot's scan fits its true place at ~0.93 and
// nowhere else in the window above ~0.56. A margin below that gap keeps the relocalisation; one
// above it turns it down as ambiguous (counted), and the pose stays with the odometry.
TEST(PoseCorrectorHold, AnAmbiguousWideRematchIsNotTaken) {
  const Kidnap plain = kidnap(false);
  ASSERT_GE(plain.relocalizations, 1u);
  const float gap = plain.scores.score - plain.scores.runner_up;
  ASSERT_GT(gap, 0.15f) << "the lab's carry is not a clear relocalisation any more";
  PoseCorrectionSettings pc = dual_settings();
  pc.relocalize_min_margin = gap - 0.1f;
  const Kidnap kept = kidnap(false, false, pc);
  EXPECT_GE(kept.relocalizations, 1u);
  EXPECT_EQ(kept.ambiguous, 0u);
  EXPECT_LT(kept.error_m, 0.15f);
  pc.relocalize_min_margin = gap + 0.05f;
  const Kidnap refused = kidnap(false, false, pc);
  EXPECT_EQ(refused.relocalizations, 0u);
  EXPECT_GE(refused.ambiguous, 1u);
  EXPECT_GT(refused.error_m, 0.3f) << "the pose stays with the odometry";
  PoseCorrectionSettings bad;
  bad.relocalize_min_margin = 1.5f;
  EXPECT_THROW(validate(bad), Error);
  bad = {};
  bad.relocalize_distinct_m = 0.0f;
  EXPECT_THROW(validate(bad), Error);
}

// A wide fit must leave the robot room to stand: its centre at least relocalize_min_clearance_m
// from the map's occupied cells. The carried robot's true place is ~0.5-1 m from the lab's
// nearest wall: the default (0.1 m) takes the re-match; a clearance above the true place's turns
// it down (counted), and the pose stays with the odometry. The real case (issue 23, belgioioso
// with one sensor): a false 1.31 m re-match into a wall's inflation, bench/RESULTS.md stop 47.
TEST(PoseCorrectorHold, AWideRematchIntoAnObstacleIsNotTaken) {
  const Kidnap plain = kidnap(false);
  ASSERT_GE(plain.relocalizations, 1u);
  EXPECT_EQ(plain.in_obstacle, 0u);
  EXPECT_LT(plain.error_m, 0.15f);
  ASSERT_GT(plain.truth_clearance_m, PoseCorrectionSettings{}.relocalize_min_clearance_m);
  ASSERT_LT(plain.truth_clearance_m, 0.95f) << "the lab's carry no longer ends near a wall";
  PoseCorrectionSettings pc = dual_settings();
  pc.relocalize_min_clearance_m = plain.truth_clearance_m + 0.05f;
  const Kidnap refused = kidnap(false, false, pc);
  pc.relocalize_min_clearance_m = 0.0f;
  expect_refused_by(&Kidnap::in_obstacle, refused, kidnap(false, false, pc));
  expect_rejected(&PoseCorrectionSettings::relocalize_min_clearance_m, {-0.1f, std::numeric_limits<float>::quiet_NaN(), 1.5f});
}

// A wide fit on the window's edge is where the window cut the score off, not a peak of it (issue
// 23, edmonton seed 5: re-matches at -11.0 and +10.8 deg in a +-10 deg window took a right pose
// 1.0 m off). The carry's larger component put on the lattice's outermost step: the default
// (half a step) turns the fit down (counted) and the pose stays with the odometry; with the check
// off (0) the same window relocalises. The default window (1 m) holds the carry well inside.
TEST(PoseCorrectorHold, AWideRematchOnTheWindowsEdgeIsNotTaken) {
  const Kidnap plain = kidnap(false);
  ASSERT_GE(plain.relocalizations, 1u);
  EXPECT_EQ(plain.at_edge, 0u);
  EXPECT_LT(plain.error_m, 0.15f);
  const float step = PoseCorrectionSettings{}.relocalize_step_m;
  const float c = std::max(std::abs(plain.offset.x), std::abs(plain.offset.y));
  std::printf("carried by (%.3f, %.3f) m\n", plain.offset.x, plain.offset.y);
  PoseCorrectionSettings pc = dual_settings();
  pc.relocalize_window_m = std::floor(c / step) * step;  // the lattice's last step at most a step short of the truth
  ASSERT_GE(pc.relocalize_window_m, 0.3f);
  const Kidnap refused = kidnap(false, false, pc);
  pc.relocalize_edge_steps = 0.0f;
  const Kidnap off = kidnap(false, false, pc);
  expect_refused_by(&Kidnap::at_edge, refused, off);
  EXPECT_LT(off.error_m, 0.15f);
  expect_rejected(&PoseCorrectionSettings::relocalize_edge_steps, {-0.5f, std::numeric_limits<float>::quiet_NaN(), 6.0f});
}

// Vision saw the jump (a gated visual increment): the wide re-match runs at the very next update,
// before the matcher has grown suspicious - and even while vision's health still confirms the
// wheels (the contradiction is the newer news).
TEST(PoseCorrectorHold, AContradictedOdometryIsRelocalisedAtTheNextUpdate) {
  const Kidnap free = kidnap(false);
  const Kidnap asked = kidnap(false, true);
  std::printf("carried 0.6 m: first relocalised at update %d on suspicion, %d when asked\n", free.first_at, asked.first_at);
  EXPECT_EQ(asked.asked, 1u);
  EXPECT_EQ(free.asked, 0u);
  EXPECT_EQ(asked.first_at, 0);
  EXPECT_LE(asked.first_at, free.first_at);
  EXPECT_LT(asked.error_m, 0.15f);
  const Kidnap both = kidnap(true, true);
  EXPECT_EQ(both.first_at, 0) << "the contradiction overrides the confirmation";
  EXPECT_LT(both.error_m, 0.15f);
}

TEST(PoseCorrectorHold, AKidnappedRobotWithVisionIsStillRelocalised) {
  const Profile p = builtin_profile("dual");
  sim::ExploreSettings s;
  s.runtime = p.runtime;
  s.seed = 1;
  s.max_time_s = duet_test::short_runs() ? 28.0 : 40.0;
  // The short variant (the sanitizer builds) is the same run cut at 28 s, the kidnap at the same
  // moment. With a kidnap at 14 s the run differs between machines: on stop 58's (AMD Zen 3) the
  // robot was pushed 0.5 m to beside a wall while turning and touched it 0.85 s later, before
  // the matcher's third suspect update relocalised it (CI's machine of stop 57 passed it).
  s.faults = {"kidnap@20"};
  s.sensor_rate_hz = 5.0;  // as duet explore renders with vision on
  s.runtime.visual_odometry.enabled = true;
  sim::SimExplore run(sim::resolve_world("lab"), p, s);
  run.run();
  const auto sum = run.summary();
  EXPECT_EQ(sum.faults.at(0).injected, 1u);
  // The view after the move is a visual jump (gated out: the scan matcher is asked for a wide
  // re-match at once) or breaks the chain of location points (a reset: vision no longer confirms
  // the wheels, and the matcher's own suspicion re-matches). Which one depends on what the
  // camera sees at the new place; either way the robot is relocalised.
  EXPECT_GE(sum.visual.gated + sum.visual.resets, 1u) << "vision did not notice the move";
  if (sum.visual.gated > 0) {
    EXPECT_GE(sum.relocalizations_asked, 1u) << "a gated jump asks for a wide re-match";
  }
  EXPECT_EQ(sum.relocalizations_held, 0u) << "vision confirmed the wheels across the move";
  EXPECT_GE(sum.relocalizations, 1u);
  EXPECT_LT(sum.pose_error_m, 0.15);
  EXPECT_EQ(sum.collisions, 0u);
}

// A stall asks for a wide re-match too: the robot drove into something where its map shows free
// floor, so its pose may be off (a wrong pose is moved if the current grid holds a clearly
// better fit; orebro seed 2 at stop 51 was not: its drifted walls had been mapped again). Here the pose is right and
// the obstacle is one the map does not hold (a 2 cm sill, which the sensors take for floor):
// the runtime asks at each stall, and the wide re-match, which moves the pose only for a clearly
// better fit, leaves it where it is (AContradictedOdometryIsRelocalisedAtTheNextUpdate: a wrong
// pose is moved).
TEST(PoseCorrectorHold, AStallAsksForAWideRematchThatKeepsARightPose) {
  // An L-shaped corridor 1.5 m wide: what lies round the corner is seen only from past the sill.
  const char* kSillRoom = R"(name: sill_corridor
floor: {min: [0, 0], max: [6.0, 6.0]}
start: [0.8, 0.8, 0.0]
walls:
  - {name: outer, points: [[0.05, 0.05], [5.95, 0.05], [5.95, 5.95], [4.45, 5.95], [4.45, 1.55], [0.05, 1.55]], closed: true}
boxes:
  - {name: sill, centre: [2.5, 0.8], size: [0.06, 1.5], height_m: 0.02}
)";
  const Profile p = builtin_profile("dual");
  sim::ExploreSettings s;
  s.runtime = p.runtime;
  s.seed = 1;
  s.max_time_s = 40.0;
  sim::SimExplore run(sim::parse_world(kSillRoom, "sill_room.yaml"), p, s);
  run.run();
  const auto sum = run.summary();
  ASSERT_GE(sum.collisions, 1u) << "the robot never met the sill: " << sum.stop_detail << " at " << sum.sim_time_s << " s, coverage " << sum.coverage;
  ASSERT_GE(sum.explorer.stalls, 1) << "no stall at the sill";
  EXPECT_GE(sum.relocalizations_asked, 1u) << "a stall asks for a wide re-match";
  EXPECT_EQ(sum.relocalizations, 0u) << "a right pose was moved";
  EXPECT_LT(sum.pose_error_max_m, 0.1);
  std::printf("sill: %zu collisions, %d stalls, %zu wide re-matches asked, pose error max %.3f m\n", sum.collisions, sum.explorer.stalls,
              sum.relocalizations_asked, sum.pose_error_max_m);
}

// A scan of space the map has not seen yet explains nothing at the prediction either, but its
// points fall on unknown cells, not on cells the map holds free: no wide re-match (a false fit of
// new walls on old ones moved freiburg-101's pose by 1.3 m / 20.7 deg, issue 23), counted; the
// pose stays with the odometry, which is right.
TEST(PoseCorrectorHold, AScanOfSpaceNotMappedYetIsNotTakenForBeingLost) {
  const Profile profile = builtin_profile("dual");
  // A 4 m x 4 m room with a crate in each corner (something to match), the robot in its middle.
  const sim::World world = sim::parse_world(R"(name: square
floor: {min: [0, 0], max: [4.2, 4.2]}
start: [2.1, 2.1, 0.0]
walls:
  - {points: [[0.05, 0.05], [4.15, 0.05], [4.15, 4.15], [0.05, 4.15]], closed: true}
boxes:
  - {centre: [0.6, 0.6], size: [0.5, 0.8], height_m: 1.0}
  - {centre: [3.6, 0.7], size: [0.6, 0.5], height_m: 1.0}
  - {centre: [3.5, 3.6], size: [0.7, 0.4], height_m: 1.0}
  - {centre: [0.7, 3.5], size: [0.4, 0.7], height_m: 1.0}
)",
                                            "square.yaml");
  const sim::RgbdRenderer renderer(world);
  std::vector<RgbdImage> images(profile.sensors.size());
  auto frames_at = [&](const Pose2& truth, std::uint64_t seed) { return render_frames(renderer, profile, truth, seed, images); };
  for (const float min_conflict : {0.05f, 0.0f}) {
    PoseCorrectionSettings pc = profile.runtime.pose_correction;
    pc.relocalize_min_conflict = min_conflict;
    Mapper mapper(profile.mapping);
    PoseCorrector corrector(profile, pc);
    // Mapped: what the sensors see from the start pose only (east and south: the front and the right sensor).
    Pose2 truth = world.start;
    double t = 0.0;
    for (int k = 0; k < 3; ++k, t += 0.5) {
      const auto frames = frames_at(truth, 10 + 2 * static_cast<std::uint64_t>(k));
      mapper.integrate(frames, to_isometry(corrector.update(frames, truth, mapper.grid(), t)));
    }
    // Half a turn: both sensors now face walls the map has never seen, west and north (odometry = truth).
    truth.theta = std::remainder(truth.theta + 3.14159265f, 2.0f * 3.14159265f);
    Pose2 at;
    for (int k = 0; k < 4; ++k, t += 0.5) {
      const auto frames = frames_at(truth, 100 + 2 * static_cast<std::uint64_t>(k));
      at = corrector.update(frames, truth, mapper.grid(), t);  // not integrated: the far side stays unseen
    }
    std::printf("matches %zu rejected %zu; ", corrector.matches(), corrector.rejected());
    std::printf("min conflict %.2f: %zu relocalised, %zu not (new space; %.0f %% on free cells), error %.3f m\n", min_conflict,
                corrector.relocalizations(), corrector.relocalizations_new_space(), 100.0f * corrector.last_conflict(),
                std::hypot(at.x - truth.x, at.y - truth.y));
    if (min_conflict > 0.0f) {
      EXPECT_GE(corrector.relocalizations_new_space(), 1u) << "a wide re-match was never due: the scene does not test the gate";
      EXPECT_LT(corrector.last_conflict(), min_conflict);
      EXPECT_EQ(corrector.relocalizations(), 0u);
      EXPECT_LT(std::hypot(at.x - truth.x, at.y - truth.y), 0.05f);
    } else {
      EXPECT_EQ(corrector.relocalizations_new_space(), 0u);
    }
  }
}

}  // namespace test_pose_corrector_hold
}  // namespace duet
