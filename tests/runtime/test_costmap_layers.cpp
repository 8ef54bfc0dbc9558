// The costmap layers (costmap_layer.hpp and the default layers): each against a hand-made grid,
// their order, the copy-free path, shift(), and a caller's layer in the Navigator.
#include <duet/kernels/error.hpp>
#include <duet/kernels/inflation.hpp>
#include <duet/runtime/navigation/contact_layer.hpp>
#include <duet/runtime/navigation/costmap_layer.hpp>
#include <duet/runtime/navigation/footprint_layer.hpp>
#include <duet/runtime/navigation/navigator.hpp>
#include <duet/runtime/navigation/recent_obstacle_layer.hpp>
#include <duet/runtime/navigation/trail_layer.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "half_known_room.hpp"

namespace {

using duet_test::half_known_room;
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

float at(const duet::OccupancyGrid& g, float x, float y) {
  const Eigen::Vector2i c = g.cell_of(Eigen::Vector2f(x, y));
  return g.logodds()[g.index(c.x(), c.y())];
}

int count_equal(const duet::OccupancyGrid& g, float v) {
  int n = 0;
  for (const float l : g.logodds()) n += l == v;
  return n;
}

/// A caller's layer: a rectangle that is an obstacle (a keep-out zone).
class KeepOut final : public duet::CostmapLayer {
 public:
  KeepOut(Eigen::Vector2f lo, Eigen::Vector2f hi) : lo_(lo), hi_(hi) {}
  std::string_view name() const override { return "keep_out"; }
  bool active() const override { return true; }
  void apply(duet::OccupancyGrid& g) override {
    ++applied;
    for (int y = 0; y < g.height(); ++y)
      for (int x = 0; x < g.width(); ++x) {
        const Eigen::Vector2f c = g.cell_center(x, y);
        if ((c.array() >= lo_.array()).all() && (c.array() <= hi_.array()).all()) g.logodds()[g.index(x, y)] = 4.0f;
      }
  }
  void shift(const duet::Pose2& D) override {
    lo_ += Eigen::Vector2f(D.x, D.y);
    hi_ += Eigen::Vector2f(D.x, D.y);
    ++shifted;
  }
  int applied = 0, shifted = 0;

 private:
  Eigen::Vector2f lo_, hi_;
};

}  // namespace

TEST(LayeredCostmap, WithoutActiveLayersInflatesTheMapAsGivenWithoutACopy) {
  const duet::OccupancyGrid g = half_known_room();
  duet::InflationSettings s;
  std::vector<std::unique_ptr<duet::CostmapLayer>> layers;
  layers.push_back(std::make_unique<duet::ContactLayer>(0.1f, 4.0f));  // no contact: inactive
  duet::LayeredCostmap cm(s, std::move(layers));
  const duet::OccupancyGrid& out = cm.update(g);
  EXPECT_EQ(&out, &g);
  EXPECT_FALSE(cm.layered());
  duet::InflatedGrid ref;
  duet::inflate(duet::GridView(g), s, ref);
  EXPECT_EQ(cm.inflated().traversable, ref.traversable);
  EXPECT_EQ(cm.inflated().clearance_m, ref.clearance_m);
}

TEST(LayeredCostmap, NullLayerIsRejectedAndBadInflationNamed) {
  std::vector<std::unique_ptr<duet::CostmapLayer>> layers;
  layers.push_back(nullptr);
  EXPECT_THROW(duet::LayeredCostmap(duet::InflationSettings{}, std::move(layers)), duet::Error);
  duet::LayeredCostmap cm(duet::InflationSettings{}, {});
  EXPECT_THROW(cm.add(nullptr), duet::Error);
  duet::InflationSettings bad;
  bad.robot_radius_m = kNaN;
  EXPECT_THROW(duet::LayeredCostmap(bad, {}), duet::Error);
}

TEST(ContactLayer, MarksADiscAndMovesWithTheMapFrame) {
  duet::OccupancyGrid g = half_known_room();
  duet::ContactLayer l(0.10f, 4.0f);
  EXPECT_FALSE(l.active());
  l.add(Eigen::Vector2f(kNaN, 1.0f));  // ignored
  EXPECT_FALSE(l.active());
  l.add(Eigen::Vector2f(2.0f, 1.5f));
  ASSERT_TRUE(l.active());
  l.apply(g);
  EXPECT_EQ(at(g, 2.0f, 1.5f), 4.0f);
  EXPECT_EQ(at(g, 2.08f, 1.5f), 4.0f);
  EXPECT_EQ(at(g, 2.2f, 1.5f), -2.0f);
  // Exactly the cells whose centre is within 0.10 m (reference: every cell of the grid).
  int ref = 0;
  for (int y = 0; y < g.height(); ++y)
    for (int x = 0; x < g.width(); ++x) ref += (g.cell_center(x, y) - Eigen::Vector2f(2.0f, 1.5f)).norm() <= 0.10f;
  EXPECT_EQ(count_equal(g, 4.0f), ref);
  l.shift(duet::Pose2{1.0f, -0.5f, 0.0f});
  EXPECT_NEAR(l.points()[0].x(), 3.0f, 1e-6f);
  EXPECT_NEAR(l.points()[0].y(), 1.0f, 1e-6f);
}

TEST(RecentObstacleLayer, MarksFreeCellsButNotNextToAnObstacleOfTheGrid) {
  duet::OccupancyGrid g = half_known_room();
  g.logodds()[g.index(20, 20)] = 3.0f;  // a wall cell of the map
  duet::RecentObstacleLayer l(/*occupied*/ 2.0f, /*marked*/ 5.0f);
  const std::vector<Eigen::Vector2f> pts = {
      g.cell_center(20, 21),            // next to the wall: adds nothing
      g.cell_center(40, 30),            // free space: marked
      g.cell_center(40, 30) + Eigen::Vector2f(0.01f, 0.01f),  // same cell: once
      Eigen::Vector2f(kNaN, 0.0f),      // dropped
      Eigen::Vector2f(-10.0f, -10.0f),  // off the grid: ignored
  };
  l.set(pts);
  EXPECT_EQ(l.points().size(), 4u);
  l.apply(g);
  EXPECT_EQ(l.cells_marked(), 1u);
  EXPECT_EQ(g.logodds()[g.index(40, 30)], 5.0f);
  EXPECT_EQ(g.logodds()[g.index(20, 21)], -2.0f);
  EXPECT_EQ(count_equal(g, 5.0f), 1);
  l.set({});
  EXPECT_FALSE(l.active());
}

TEST(TrailLayer, ClearsOnlyUnknownCellsWhollyUnderTheBodyAndTheStartDisc) {
  duet::OccupancyGrid g(0.05f, Eigen::Vector2f(0.0f, 0.0f), 80, 80);  // all unknown
  g.logodds()[g.index(40, 40)] = 3.0f;                               // a known obstacle under the trail
  duet::TrailLayer l(/*body*/ 0.2f, /*start*/ 0.3f, /*free*/ -2.0f);
  l.add(Eigen::Vector2f(1.0f, 1.0f));
  l.add(Eigen::Vector2f(1.02f, 1.0f));  // closer than 0.05 m to the last: dropped
  l.add(Eigen::Vector2f(kNaN, 1.0f));   // dropped
  l.add(Eigen::Vector2f(3.0f, 3.0f));
  ASSERT_EQ(l.points().size(), 2u);
  l.apply(g);
  EXPECT_EQ(g.logodds()[g.index(40, 40)], 3.0f);  // known cells keep their value
  // Start: every cell centre within 0.3 + 0.05 m of (1, 1) is free; later points: within 0.2 - 0.7072 * 0.05.
  const float later_r = 0.2f - 0.7072f * 0.05f;
  for (int y = 0; y < g.height(); ++y)
    for (int x = 0; x < g.width(); ++x) {
      if (x == 40 && y == 40) continue;
      const Eigen::Vector2f c = g.cell_center(x, y);
      const bool want = (c - Eigen::Vector2f(1.0f, 1.0f)).norm() <= 0.35f || (c - Eigen::Vector2f(3.0f, 3.0f)).norm() <= later_r;
      ASSERT_EQ(!std::isnan(g.logodds()[g.index(x, y)]), want) << x << "," << y;
    }
}

// The trail's cells are cached per grid geometry (a patrol's map update costs the cells, not the
// trail's length): whatever the sequence of points, grids and shifts, apply() gives what a
// fresh layer with the same points gives (the plain definition), cell for cell.
TEST(TrailLayer, CachedCellsEqualAFreshLayerAcrossPointsGeometriesAndShifts) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(0.3f, 3.7f);
  duet::TrailLayer cached(0.2f, 0.3f, -2.0f);
  std::vector<Eigen::Vector2f> points;
  auto check = [&](const duet::OccupancyGrid& blank, const char* when) {
    duet::OccupancyGrid a = blank, b = blank;
    cached.apply(a);
    duet::TrailLayer fresh(0.2f, 0.3f, -2.0f);
    for (const Eigen::Vector2f& p : cached.points()) fresh.add(p);
    ASSERT_EQ(fresh.points().size(), cached.points().size());
    fresh.apply(b);
    int cleared = 0;
    for (std::size_t i = 0; i < a.logodds().size(); ++i) {
      const float x = a.logodds()[i], y = b.logodds()[i];
      ASSERT_TRUE((std::isnan(x) && std::isnan(y)) || x == y) << when << ": cell " << i;
      cleared += !std::isnan(x) && std::isnan(blank.logodds()[i]);
    }
    EXPECT_GT(cleared, 0) << when;
  };
  duet::OccupancyGrid g1(0.05f, Eigen::Vector2f(0.0f, 0.0f), 80, 80);  // all unknown
  g1.logodds()[g1.index(30, 30)] = 3.0f;                              // a known cell
  duet::OccupancyGrid g2(0.05f, Eigen::Vector2f(-0.5f, -0.25f), 100, 90);  // the map grew
  for (int round = 0; round < 6; ++round) {
    for (int k = 0; k < 20; ++k) cached.add(Eigen::Vector2f(u(rng), u(rng)));
    check(round < 3 ? g1 : g2, "points added");
    check(round < 3 ? g1 : g2, "again, nothing new");
    if (round == 4) {
      cached.shift(duet::Pose2{0.1f, -0.05f, 0.05f});
      check(g2, "after a shift");
    }
  }
}

TEST(LayeredCostmap, LayersApplyInOrderOnOneCopy) {
  duet::OccupancyGrid g = half_known_room();
  std::vector<std::unique_ptr<duet::CostmapLayer>> layers;
  auto contacts = std::make_unique<duet::ContactLayer>(0.10f, 4.0f);
  contacts->add(Eigen::Vector2f(2.0f, 1.5f));
  auto recent = std::make_unique<duet::RecentObstacleLayer>(2.0f, 5.0f);
  const std::vector<Eigen::Vector2f> pts = {Eigen::Vector2f(2.12f, 1.5f), Eigen::Vector2f(3.0f, 1.0f)};
  recent->set(pts);
  duet::RecentObstacleLayer* r = recent.get();
  layers.push_back(std::move(contacts));
  layers.push_back(std::move(recent));
  duet::LayeredCostmap cm(duet::InflationSettings{}, std::move(layers));
  const duet::OccupancyGrid& out = cm.update(g);
  ASSERT_TRUE(cm.layered());
  EXPECT_EQ(&out, &cm.grid());
  // The recent layer saw the contact: the point next to it adds nothing, the other is marked.
  EXPECT_EQ(r->cells_marked(), 1u);
  EXPECT_EQ(at(out, 3.0f, 1.0f), 5.0f);
  EXPECT_EQ(at(out, 2.0f, 1.5f), 4.0f);
  EXPECT_EQ(at(g, 2.0f, 1.5f), -2.0f);  // the map itself is untouched
  EXPECT_EQ(cm.inflated().traversable[cm.inflated().index(cm.inflated().cell_of(Eigen::Vector2f(3.0f, 1.0f)).x(),
                                                          cm.inflated().cell_of(Eigen::Vector2f(3.0f, 1.0f)).y())],
            0);
}

TEST(Navigator, CallersLayerIsPlannedAroundAndShifted) {
  const duet::Profile p = duet_test::frontier_only_profile();
  const duet::Pose2 robot{0.5f, 1.5f, 0.0f};
  // Without the layer: a straight path along y = 1.5 to a goal beyond x = 2.
  auto plain = std::make_unique<duet::Navigator>(p, p.runtime.explorer);
  plain->update_map(half_known_room(), robot, 0.0);
  plain->decide(robot, 0.0);
  ASSERT_TRUE(plain->goal().has_value());
  ASSERT_GT(plain->goal()->x, 2.5f);
  // A wall of keep-out from y = 0.5 to 2.5 at x in [1.8, 2.0]: the path goes round it.
  auto keep = std::make_unique<KeepOut>(Eigen::Vector2f(1.8f, 0.5f), Eigen::Vector2f(2.0f, 2.5f));
  KeepOut* k = keep.get();
  duet::Navigator nav(p, p.runtime.explorer);
  nav.add_layer(duet::CostmapKind::kPlanning, std::move(keep));
  nav.update_map(half_known_room(), robot, 0.0);
  EXPECT_EQ(k->applied, 1);
  EXPECT_TRUE(nav.costmap(duet::CostmapKind::kPlanning).layered());
  nav.decide(robot, 0.0);
  ASSERT_TRUE(nav.goal().has_value());
  ASSERT_FALSE(nav.path().empty());
  bool around = false;
  for (const Eigen::Vector2f& q : nav.path()) {
    EXPECT_FALSE(q.x() >= 1.8f && q.x() <= 2.0f && q.y() >= 0.5f && q.y() <= 2.5f) << q.transpose();
    around |= q.y() < 0.5f || q.y() > 2.5f;
  }
  EXPECT_TRUE(around);
  // The local costmap sees the planning costmap's layers too.
  const duet::InflatedGrid& local = nav.local_grid();
  const Eigen::Vector2i c = local.cell_of(Eigen::Vector2f(1.9f, 1.5f));
  EXPECT_EQ(local.traversable[local.index(c.x(), c.y())], 0);
  nav.shift(duet::Pose2{0.1f, 0.0f, 0.0f});
  EXPECT_EQ(k->shifted, 1);
}

TEST(FootprintLayer, ClearsOnlyOccupiedCellsWhollyUnderTheBody) {
  duet::OccupancyGrid g(0.05f, Eigen::Vector2f(0.0f, 0.0f), 60, 60);
  for (int y = 0; y < 60; ++y)
    for (int x = 0; x < 60; ++x) g.logodds()[g.index(x, y)] = ((x + y) % 3 == 0) ? 3.0f : ((x + y) % 3 == 1 ? -2.0f : kNaN);
  const duet::OccupancyGrid before = g;
  duet::FootprintLayer l(/*body*/ 0.2f, /*occupied*/ 0.85f, /*free*/ -2.5f);
  EXPECT_FALSE(l.active());
  l.apply(g);  // inactive: nothing changes
  EXPECT_EQ(l.cells_cleared(), 0u);
  const Eigen::Vector2f centre(1.5f, 1.5f);
  const float r = 0.2f - 0.7072f * 0.05f;
  std::size_t want = 0;
  for (int y = 0; y < 60; ++y)
    for (int x = 0; x < 60; ++x) want += (g.cell_center(x, y) - centre).norm() <= r && before.logodds()[before.index(x, y)] >= 0.85f;
  ASSERT_GT(want, 5u);
  EXPECT_EQ(l.occupied_under(g, centre), want);
  l.set(centre);
  EXPECT_TRUE(l.active());
  l.apply(g);
  EXPECT_EQ(l.cells_cleared(), want);
  for (int y = 0; y < 60; ++y)
    for (int x = 0; x < 60; ++x) {
      const float b = before.logodds()[before.index(x, y)], a = g.logodds()[g.index(x, y)];
      const bool under = (g.cell_center(x, y) - centre).norm() <= r;
      if (under && b >= 0.85f) EXPECT_EQ(a, -2.5f) << x << "," << y;
      else if (std::isnan(b)) EXPECT_TRUE(std::isnan(a)) << x << "," << y;  // unknown stays unknown
      else EXPECT_EQ(a, b) << x << "," << y;                                 // free, and occupied off the body
    }
  // The footprint moves with the map frame; reset() makes the layer inactive.
  l.shift(duet::Pose2{0.5f, 0.0f, 0.0f});
  duet::OccupancyGrid g2 = before;
  l.apply(g2);
  EXPECT_EQ(l.cells_cleared(), l.occupied_under(before, Eigen::Vector2f(2.0f, 1.5f)));
  EXPECT_EQ(at(g2, 2.0f, 1.5f) >= 0.85f, false);
  l.reset();
  EXPECT_FALSE(l.active());
  // A body off the grid, a non-finite position, an empty grid: nothing.
  EXPECT_EQ(l.occupied_under(before, Eigen::Vector2f(-5.0f, -5.0f)), 0u);
  EXPECT_EQ(l.occupied_under(before, Eigen::Vector2f(kNaN, 1.0f)), 0u);
  EXPECT_EQ(l.occupied_under(duet::OccupancyGrid(0.05f), centre), 0u);
  l.set(Eigen::Vector2f(kNaN, 1.0f));
  EXPECT_FALSE(l.active());
  // Bad settings are named.
  EXPECT_THROW(duet::FootprintLayer(0.0f, 0.85f, -2.5f), duet::Error);
  EXPECT_THROW(duet::FootprintLayer(0.2f, -3.0f, -2.5f), duet::Error);
  EXPECT_THROW(duet::FootprintLayer(kNaN, 0.85f, -2.5f), duet::Error);
}

TEST(Navigator, AnObstacleUnderTheEstimatedBodyDoesNotPinTheRobot) {
  // A post 0.09 m from the estimated centre (a pose a few cm off, a post kept near the sensor):
  // without the footprint cleared every rollout of the dynamic window starts in the obstacle and
  // the robot stays where it is; with it the window finds a way, and the post is an obstacle of
  // the costmaps again once the robot has left it (the map keeps it throughout).
  duet::OccupancyGrid map = half_known_room();
  const duet::Pose2 robot{1.0f, 1.5f, 0.0f};
  const Eigen::Vector2i post = map.cell_of(Eigen::Vector2f(1.09f, 1.5f));
  map.logodds()[map.index(post.x(), post.y())] = 3.5f;
  const duet::Profile p = duet_test::frontier_only_profile();
  for (const bool clear : {false, true}) {
    SCOPED_TRACE(clear ? "clear_footprint" : "no clear_footprint");
    duet::ExplorerSettings es = p.runtime.explorer;
    es.clear_footprint = clear;
    duet::Navigator nav(p, es);
    nav.update_map(map, robot, 0.0);
    nav.decide(robot, 0.0);
    ASSERT_TRUE(nav.goal().has_value());
    ASSERT_FALSE(nav.path().empty());
    const duet::NavPlanView v = nav.view();
    duet::DwaState st;
    duet::DwaWorkspace ws;
    const duet::DwaResult local = duet::dwa_step(v.local->clearance(), robot, duet::Twist{}, v.path, v.dwa, st, ws);
    st = {};
    const duet::DwaResult planning = duet::dwa_step(v.planning->clearance(), robot, duet::Twist{}, v.path, v.dwa, st, ws);
    if (!clear) {
      EXPECT_EQ(local.status, duet::DwaStatus::kNoValidTrajectory) << "the post does not pin the robot: the scene tests nothing";
      EXPECT_EQ(planning.status, duet::DwaStatus::kNoValidTrajectory);
      EXPECT_EQ(nav.stats().footprint_clearings, 0);
      continue;
    }
    EXPECT_TRUE(local.status == duet::DwaStatus::kOk || local.status == duet::DwaStatus::kRotateInPlace) << duet::to_string(local.status);
    EXPECT_GT(std::fabs(local.cmd.v) + std::fabs(local.cmd.omega), 0.0f);
    EXPECT_EQ(nav.stats().footprint_clearings, 1);
    EXPECT_EQ(map.logodds()[map.index(post.x(), post.y())], 3.5f);  // the map keeps the post
    // 1 m on: the post is an obstacle of the costmaps again.
    nav.update_map(map, duet::Pose2{2.0f, 1.5f, 0.0f}, 1.0);
    const duet::InflatedGrid& later = nav.planning_grid();
    EXPECT_EQ(later.traversable[later.index(post.x(), post.y())], 0);
    EXPECT_EQ(nav.stats().footprint_clearings, 1);
  }
}
