// Thin obstacles end to end (issue 23): a post 5 cm across - a table leg, a coat stand, a
// railing's upright - must be in the 2D grid once the robot has seen it, or the planner drives
// through it. Found on belgioioso (`duet explore -w ../shared/data/maps/belgioioso.yaml -s 1`):
// every collision there hit one isolated 5 cm post that the 3D cloud held and the grid did not.
#include "sanitized.hpp"

#include <duet/kernels/grid.hpp>
#include <duet/runtime/config/profile.hpp>
#include <duet/runtime/mapping/mapper.hpp>
#include <duet/runtime/robot/robot_io.hpp>
#include <duet/sim/renderer.hpp>
#include <duet/sim/sim_explore.hpp>
#include <duet/sim/world.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <cstdio>
#include <string>
#include <vector>

namespace test_thin_obstacles {
namespace {

// A 6 m x 4.5 m room with four posts 5 cm across, 2.5 m high (as a map-made world builds them), away from the walls.
const char* kPostRoom = R"(name: post_room
floor: {min: [0, 0], max: [6.0, 4.5]}
start: [0.8, 2.25, 0.0]
walls:
  - {name: outer, points: [[0.05, 0.05], [5.95, 0.05], [5.95, 4.45], [0.05, 4.45]], closed: true}
boxes:
  - {name: post a, centre: [2.0, 1.2], size: [0.05, 0.05], height_m: 2.5}
  - {name: post b, centre: [3.1, 3.1], size: [0.05, 0.05], height_m: 2.5}
  - {name: post c, centre: [4.3, 1.6], size: [0.05, 0.05], height_m: 2.5}
  - {name: post d, centre: [4.9, 3.4], size: [0.05, 0.05], height_m: 2.5}
)";

const std::vector<Eigen::Vector2f> kPosts{{2.0f, 1.2f}, {3.1f, 3.1f}, {4.3f, 1.6f}, {4.9f, 3.4f}};

// The highest log-odds of the grid cells whose centres lie within r of xy (NaN: none observed).
float max_logodds_near(const duet::OccupancyGrid& g, const Eigen::Vector2f& xy, float r) {
  float best = NAN;
  const Eigen::Vector2i c = g.cell_of(xy);
  const int rc = static_cast<int>(std::ceil(r / g.resolution()));
  for (int y = c.y() - rc; y <= c.y() + rc; ++y)
    for (int x = c.x() - rc; x <= c.x() + rc; ++x) {
      if (!g.in_bounds(x, y) || (g.cell_center(x, y) - xy).norm() > r) continue;
      const float l = g.at(x, y);
      if (!std::isnan(l) && !(l <= best)) best = l;
    }
  return best;
}

// Maps the depth the profile's sensors see at each pose (rendered, noise on) with the profile's
// mapper and returns the highest log-odds within 8 cm of `post` after each pose.
std::vector<float> pass_post(const duet::Profile& prof, const std::vector<duet::Pose2>& poses, const Eigen::Vector2f& post) {
  const duet::sim::World w = duet::sim::parse_world(kPostRoom, "post_room.yaml");
  const duet::sim::RgbdRenderer r(w);
  duet::Mapper m(prof.mapping);
  std::vector<duet::RgbdImage> imgs(prof.sensors.size());
  std::vector<float> out;
  std::uint64_t seed = 1;
  for (const duet::Pose2& p : poses) {
    const Eigen::Isometry3f T = duet::to_isometry(p);
    std::vector<duet::SensorFrame> frames;
    for (std::size_t i = 0; i < prof.sensors.size(); ++i) {
      r.render_depth_only(prof.sensors[i], T * prof.sensors[i].T_robot_optical(), ++seed, imgs[i]);
      frames.push_back(duet::frame_view(imgs[i], prof.sensors[i], prof.sensors[i].T_robot_optical()));
    }
    m.integrate(frames, T);
    out.push_back(max_logodds_near(m.grid(), post, 0.08f));
  }
  return out;
}

}  // namespace

TEST(ThinObstacles, APostTooNearForTheSensorsIsNotErasedByTheRaysPassingBesideIt) {
  // Found on belgioioso (seed 2, true pose): the robot saw a 5 cm post from 1.8 m, drove past it
  // and turned; once nearer than the Kinect's 0.5 m minimum depth the post returned no point,
  // the rays to the floor beside it cleared its cell at each map update, and the robot hit it.
  // Here: drive past post a (2.0, 1.2) with it 0.3 m to the right, then turn twice on the spot.
  const Eigen::Vector2f post(2.0f, 1.2f);
  std::vector<duet::Pose2> poses;
  for (float x = 0.6f; x <= 2.0f + 1e-3f; x += 0.1f) poses.push_back({x, 1.5f, 0.0f});
  for (int k = 1; k <= 48; ++k) poses.push_back({2.0f, 1.5f, -static_cast<float>(k) * std::numbers::pi_v<float> / 12.0f});
  for (const char* name : {"dual_kinect_kobuki", "single_kinect_kobuki"}) {
    SCOPED_TRACE(name);
    duet::Profile prof = duet::builtin_profile(name);
    const float occupied = prof.exploration.cells.occupied_logodds;
    // The profiles' value (the minimum depth plus two cells), set here so the test holds if they change.
    prof.mapping.grid_update.keep_occupied_within_m = 0.6f;
    const std::vector<float> kept = pass_post(prof, poses, post);
    prof.mapping.grid_update.keep_occupied_within_m = 0.0f;
    const std::vector<float> erased = pass_post(prof, poses, post);
    // Seen on the way (occupied at some pose), and still occupied at the end of the turn.
    const auto seen = std::find_if(kept.begin(), kept.end(), [&](float l) { return l >= occupied; });
    ASSERT_NE(seen, kept.end()) << "the post was never occupied: the scene does not test what it should";
    for (auto it = seen; it != kept.end(); ++it)
      EXPECT_GE(*it, occupied) << "pose " << (it - kept.begin()) << ": the post was erased";
    // Without it the same drive erases the post (so the scene exercises the rule).
    EXPECT_LT(erased.back(), occupied) << "keep_occupied_within_m 0 kept the post too: the scene is not the belgioioso case";
    std::printf("%s: post log-odds at the end %.2f (kept) / %.2f (keep_occupied_within_m 0)\n", name, kept.back(), erased.back());
  }
}

TEST(ThinObstacles, PostsFiveCentimetresAcrossAreOccupiedInTheGridAndNeverHit) {
  for (const char* profile : {"dual_kinect_kobuki", "single_kinect_kobuki"}) {
    SCOPED_TRACE(profile);
    duet::sim::ExploreSettings es;
    es.seed = 1;
    es.max_time_s = duet_test::short_runs() ? 90.0 : 180.0;
    duet::sim::SimExplore run(duet::sim::parse_world(kPostRoom, "post_room.yaml"), duet::builtin_profile(profile), es);
    run.run();
    const auto s = run.summary();
    std::printf("%s: %.1f s, coverage %.3f, collisions %zu: %s\n", profile, s.sim_time_s, s.coverage, s.collisions, s.stop_detail.c_str());
    EXPECT_EQ(s.collisions, 0u) << s.stop_detail;
    ASSERT_GE(s.coverage, 0.8) << "the room was not explored, so the posts need not have been seen: " << s.stop_detail;
    const duet::CellThresholds cells = duet::builtin_profile(profile).exploration.cells;
    for (const Eigen::Vector2f& p : kPosts) {
      // The post's own cell or a neighbour (the map's pose is a few cm off the true one).
      const float l = max_logodds_near(run.mapper().grid(), p, 0.08f);
      std::printf("  post (%.1f, %.1f): max log-odds %.2f within 8 cm\n", p.x(), p.y(), l);
      EXPECT_GE(l, cells.occupied_logodds) << "the post at (" << p.x() << ", " << p.y() << ") is not occupied in the grid";
    }
  }
}

}  // namespace test_thin_obstacles
