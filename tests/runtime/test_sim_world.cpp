// Simulated worlds: the lab replica keeps the paper's facts (§4.2, Fig. 9), the loaders reject
// bad files with the file and the key, and the geometry queries agree with plain references.
#include <duet/kernels/error.hpp>
#include <duet/runtime/io/grid_io.hpp>
#include <duet/runtime/io/output.hpp>
#include <duet/sim/world.hpp>

#include <gtest/gtest.h>

#include "runtime_test_util.hpp"

#include <cmath>
#include <filesystem>
#include <random>
#include <string>

namespace fs = std::filesystem;
using duet::sim::World;

namespace {

using duet_test::TempDir;

World load_text(const std::string& text) { return duet::sim::parse_world(text, "test.yaml"); }

std::string error_of(const std::string& text) {
  try {
    (void)load_text(text);
  } catch (const duet::Error& e) {
    return e.what();
  }
  ADD_FAILURE() << "no error for:\n" << text;
  return {};
}

const char* kMinimal = R"(name: tiny
floor: {min: [0, 0], max: [4, 3]}
start: [0.5, 0.5, 0]
)";

// Distance from p to the nearest solid of `w` (any height), by brute force over dense samples
// of every polygon edge: the reference for clearance().
float brute_clearance(const World& w, const Eigen::Vector2f& p) {
  float best = std::min({p.x() - w.floor.min.x(), p.y() - w.floor.min.y(), w.floor.max.x() - p.x(), w.floor.max.y() - p.y()});
  for (const auto& s : w.solids)
    for (std::size_t i = 0; i < s.polygon.size(); ++i) {
      const Eigen::Vector2f a = s.polygon[i], b = s.polygon[(i + 1) % s.polygon.size()];
      for (int k = 0; k <= 2000; ++k) best = std::min(best, (a + (b - a) * (static_cast<float>(k) / 2000.0f) - p).norm());
    }
  return best;
}

}  // namespace

TEST(SimWorldLab, KeepsThePapersFacts) {
  const World lab = duet::sim::builtin_world("lab");
  EXPECT_EQ(lab.name, "lab");
  EXPECT_NEAR(lab.floor.max.x() - lab.floor.min.x(), 11.04f, 1e-5f);
  EXPECT_NEAR(lab.floor.max.y() - lab.floor.min.y(), 7.93f, 1e-5f);
  ASSERT_TRUE(lab.start_region.has_value());
  ASSERT_TRUE(lab.target_region.has_value());
  const Eigen::Vector2f sr = lab.start_region->max - lab.start_region->min;
  EXPECT_NEAR(sr.x(), 1.18f, 1e-5f);
  EXPECT_NEAR(sr.y(), 1.12f, 1e-5f);
  const Eigen::Vector2f tr = lab.target_region->max - lab.target_region->min;
  EXPECT_NEAR(tr.x(), 2.68f, 1e-5f);
  EXPECT_NEAR(tr.y(), 2.44f, 1e-5f);
  EXPECT_TRUE(lab.start_region->contains({lab.start.x, lab.start.y}));
  // Aisle widths (§4.2): half-width = clearance at the aisle's centre line.
  EXPECT_NEAR(duet::sim::clearance(lab, {10.225f, 5.8f}), 1.43f / 2, 1e-4f);  // scene (ii)
  EXPECT_NEAR(duet::sim::clearance(lab, {8.0f, 2.575f}), 0.85f / 2, 1e-4f);   // scenes (iii)/(iv)
  EXPECT_NEAR(duet::sim::clearance(lab, {6.95f, 4.5f}), 0.90f / 2, 1e-4f);    // scene (v)
  EXPECT_NEAR(duet::sim::clearance(lab, {2.3f, 5.81f}), 0.78f / 2, 1e-4f);    // scene (vii)
  // Baffle plates are 1.5 m high (above the sensors' vertical range at the aisle).
  int baffles = 0;
  for (const auto& s : lab.solids)
    if (s.name.find("baffle") != std::string::npos) {
      ++baffles;
      EXPECT_FLOAT_EQ(s.z_max_m, 1.5f) << s.name;
    }
  EXPECT_GE(baffles, 4);
  // The robot fits at the start, and cannot stand inside a wall.
  EXPECT_FALSE(duet::sim::collides(lab, {lab.start.x, lab.start.y}, 0.23f));
  EXPECT_TRUE(duet::sim::collides(lab, {9.485f, 4.0f}, 0.01f));  // in the baffle
  EXPECT_TRUE(duet::sim::collides(lab, {0.15f, 4.0f}, 0.1f));    // touching the outer wall
}

TEST(SimWorldLab, EveryRegionIsReachableAndTheRouteIsSingleConnected) {
  const World lab = duet::sim::builtin_world("lab");
  const auto truth = duet::sim::rasterize(lab, 0.05f);
  const auto mask = duet::sim::reachable_free_mask(truth, lab.start, 0.20f, 5.0f);
  auto in_mask = [&](float x, float y) {
    const int cx = static_cast<int>((x - truth.origin.x()) / truth.resolution_m);
    const int cy = static_cast<int>((y - truth.origin.y()) / truth.resolution_m);
    return mask[static_cast<std::size_t>(cy) * truth.width + cx] != 0;
  };
  EXPECT_TRUE(in_mask(lab.target_region->centre().x(), lab.target_region->centre().y()));
  EXPECT_TRUE(in_mask(10.2f, 4.5f));  // aisle ii
  EXPECT_TRUE(in_mask(8.0f, 2.5f));   // aisle iii/iv
  EXPECT_TRUE(in_mask(2.3f, 5.8f));   // scene vii aisle
  EXPECT_TRUE(in_mask(9.0f, 1.8f));   // behind the table, south of the aisle
  std::size_t free = 0, reach = 0;
  for (std::size_t i = 0; i < mask.size(); ++i) {
    free += truth.occupied[i] ? 0 : 1;
    reach += mask[i];
  }
  const double cell_area = 0.05 * 0.05;
  // Most of the lab's free floor is reachable or seen from reachable places.
  EXPECT_GT(static_cast<double>(reach) * cell_area, 60.0);
  EXPECT_LE(reach, free);
  // Single connected route: blocking aisle iii/iv cuts the start off from the target.
  World blocked = lab;
  duet::sim::Solid plug;
  plug.name = "plug";
  plug.polygon = {{8.0f, 2.15f}, {8.1f, 2.15f}, {8.1f, 3.0f}, {8.0f, 3.0f}};
  blocked.solids.push_back(plug);
  duet::sim::validate(blocked);
  const auto t2 = duet::sim::rasterize(blocked, 0.05f);
  const auto m2 = duet::sim::reachable_free_mask(t2, blocked.start, 0.20f, 0.0f);
  const auto tc = lab.target_region->centre();
  const int cx = static_cast<int>((tc.x() - t2.origin.x()) / 0.05f), cy = static_cast<int>((tc.y() - t2.origin.y()) / 0.05f);
  EXPECT_EQ(m2[static_cast<std::size_t>(cy) * t2.width + cx], 0);
}

TEST(SimWorld, ClearanceMatchesBruteForce) {
  World w = load_text(std::string(kMinimal) + R"(boxes:
  - {centre: [2.5, 1.5], size: [0.6, 0.3], yaw_deg: 30}
polygons:
  - {points: [[0.5, 2.0], [1.5, 2.0], [1.0, 2.6], [0.8, 2.2]]}
)");
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> ux(0.01f, 3.99f), uy(0.01f, 2.99f);
  for (int i = 0; i < 300; ++i) {
    const Eigen::Vector2f p(ux(rng), uy(rng));
    const float c = duet::sim::clearance(w, p);
    bool inside = false;
    for (const auto& s : w.solids) {
      // Inside test by ray parity against a reference implementation of the same rule.
      bool in = false;
      for (std::size_t a = 0, n = s.polygon.size(), b = n - 1; a < n; b = a++) {
        const auto& pa = s.polygon[a];
        const auto& pb = s.polygon[b];
        if ((pa.y() > p.y()) != (pb.y() > p.y()) && p.x() < pa.x() + (p.y() - pa.y()) * (pb.x() - pa.x()) / (pb.y() - pa.y()))
          in = !in;
      }
      inside = inside || in;
    }
    if (inside) {
      EXPECT_EQ(c, 0.0f);
      EXPECT_TRUE(duet::sim::collides(w, p, 0.0f));
    } else {
      EXPECT_NEAR(c, brute_clearance(w, p), 2e-3f) << p.transpose();
      // collides() is the disc test: consistent with clearance.
      if (c > 0.011f) {
        EXPECT_FALSE(duet::sim::collides(w, p, c - 0.01f)) << p.transpose();
      }
      EXPECT_TRUE(duet::sim::collides(w, p, c + 0.01f)) << p.transpose();
    }
  }
  // Height ranges: a solid above the robot's body does not collide.
  World high = load_text(std::string(kMinimal) + "boxes:\n  - {centre: [2.5, 1.5], size: [0.5, 0.5], z_m: [0.8, 1.0]}\n");
  EXPECT_FALSE(duet::sim::collides(high, {2.5f, 1.5f}, 0.1f, 0.0f, 0.6f));
  EXPECT_TRUE(duet::sim::collides(high, {2.5f, 1.5f}, 0.1f, 0.0f, 0.9f));
  // Non-finite centre: a collision, never UB.
  EXPECT_TRUE(duet::sim::collides(high, {NAN, 1.0f}, 0.1f));
}

TEST(SimWorld, RasterizeCoversEveryOverlappingCellAndNoOther) {
  World w = load_text(std::string(kMinimal) + "boxes:\n  - {centre: [2.03, 1.47], size: [0.9, 0.4], yaw_deg: 23}\n");
  const float res = 0.05f;
  const auto g = duet::sim::rasterize(w, res);
  ASSERT_EQ(g.width, 80);
  ASSERT_EQ(g.height, 60);
  const auto& poly = w.solids[0].polygon;
  // Reference: a cell overlaps the box when any of 20x20 sample points inside it is inside the
  // box (tolerate disagreement only for cells the box barely touches).
  int marked = 0;
  for (int y = 0; y < g.height; ++y)
    for (int x = 0; x < g.width; ++x) {
      int hits = 0;
      for (int sy = 0; sy < 20; ++sy)
        for (int sx = 0; sx < 20; ++sx) {
          const Eigen::Vector2f p = g.origin + Eigen::Vector2f((x + (sx + 0.5f) / 20.0f) * res, (y + (sy + 0.5f) / 20.0f) * res);
          // inside the rectangle: project on its axes
          const Eigen::Vector2f c(2.03f, 1.47f);
          const float yaw = 23.0f * 3.14159265f / 180.0f;
          const Eigen::Vector2f d = p - c;
          const float u = d.dot(Eigen::Vector2f(std::cos(yaw), std::sin(yaw)));
          const float v = d.dot(Eigen::Vector2f(-std::sin(yaw), std::cos(yaw)));
          hits += (std::fabs(u) < 0.45f && std::fabs(v) < 0.2f) ? 1 : 0;
        }
      marked += g.at(x, y);
      if (hits >= 2) {
        EXPECT_EQ(g.at(x, y), 1) << x << "," << y;
      }
      if (g.at(x, y) == 1 && hits == 0) {
        // Marked without a sample inside: the box may only graze it.
        const Eigen::Vector2f cc = g.origin + Eigen::Vector2f((x + 0.5f) * res, (y + 0.5f) * res);
        float dmin = 1e9f;
        for (std::size_t i = 0; i < poly.size(); ++i) {
          const Eigen::Vector2f a = poly[i], b = poly[(i + 1) % poly.size()];
          const float t = std::clamp((cc - a).dot(b - a) / (b - a).squaredNorm(), 0.0f, 1.0f);
          dmin = std::min(dmin, (a + t * (b - a) - cc).norm());
        }
        EXPECT_LE(dmin, res * 0.7072f) << x << "," << y;
      }
    }
  // Area: 0.36 m^2 = 144 cells; a rotated box's cover is larger by its boundary cells.
  EXPECT_GT(marked, 144);
  EXPECT_LT(marked, 144 + 2 * (0.9 + 0.4) / res * 1.5);
  // An axis-aligned box on cell boundaries covers exactly its cells.
  World a = load_text(std::string(kMinimal) + "boxes:\n  - {min: [1.0, 1.0], max: [1.5, 1.25]}\n");
  const auto ga = duet::sim::rasterize(a, res);
  int count = 0;
  for (int y = 0; y < ga.height; ++y)
    for (int x = 0; x < ga.width; ++x) {
      const bool in = x >= 20 && x < 30 && y >= 20 && y < 25;
      EXPECT_EQ(ga.at(x, y), in ? 1 : 0) << x << "," << y;
      count += ga.at(x, y);
    }
  EXPECT_EQ(count, 50);
  EXPECT_THROW((void)duet::sim::rasterize(a, 0.0f), duet::Error);
}

TEST(SimWorld, ReachableMaskStopsAtGapsNarrowerThanTheRobot) {
  // Two rooms; the wall between them has a 0.3 m gap: a 0.2 m radius robot cannot pass, but
  // sees 1 m into the second room through it.
  World w = load_text(R"(name: two rooms
floor: {min: [0, 0], max: [6, 2]}
start: [1, 1, 0]
boxes:
  - {min: [2.95, 0.0], max: [3.05, 0.85]}
  - {min: [2.95, 1.15], max: [3.05, 2.0]}
)");
  const auto g = duet::sim::rasterize(w, 0.05f);
  const auto no_sight = duet::sim::reachable_free_mask(g, w.start, 0.2f, 0.0f);
  const auto sight = duet::sim::reachable_free_mask(g, w.start, 0.2f, 1.0f);
  auto at = [&](const std::vector<std::uint8_t>& m, float x, float y) {
    return m[static_cast<std::size_t>(y / 0.05f) * g.width + static_cast<std::size_t>(x / 0.05f)];
  };
  EXPECT_EQ(at(no_sight, 1.0f, 1.0f), 1);
  EXPECT_EQ(at(no_sight, 2.7f, 1.0f), 1);
  EXPECT_EQ(at(no_sight, 3.5f, 1.0f), 0);  // the other room
  EXPECT_EQ(at(no_sight, 0.1f, 0.1f), 0);  // corner: the robot's centre cannot get there
  EXPECT_EQ(at(sight, 0.1f, 0.1f), 1);     // but it is seen
  EXPECT_EQ(at(sight, 3.3f, 1.0f), 1);     // seen through the gap
  EXPECT_EQ(at(sight, 5.5f, 1.0f), 0);     // too far
  // Widen the gap to 0.5 m: the second room becomes reachable.
  World wide = w;
  wide.solids[0].polygon = {{2.95f, 0.0f}, {3.05f, 0.0f}, {3.05f, 0.75f}, {2.95f, 0.75f}};
  wide.solids[1].polygon = {{2.95f, 1.25f}, {3.05f, 1.25f}, {3.05f, 2.0f}, {2.95f, 2.0f}};
  const auto gw = duet::sim::rasterize(wide, 0.05f);
  const auto mw = duet::sim::reachable_free_mask(gw, wide.start, 0.2f, 0.0f);
  EXPECT_EQ(mw[static_cast<std::size_t>(1.0f / 0.05f) * gw.width + static_cast<std::size_t>(5.5f / 0.05f)], 1);
}

TEST(SimWorld, FileErrorsNameTheFileAndTheKey) {
  const std::string base = kMinimal;
  auto has = [](const std::string& msg, const std::string& part) {
    EXPECT_NE(msg.find(part), std::string::npos) << "'" << part << "' not in: " << msg;
  };
  std::string e = error_of(base + "boxes:\n  - {centre: [1, 1], size: [1, 1], colour: 3}\n");
  has(e, "test.yaml:");
  has(e, "boxes[0].colour");
  has(e, "unknown key");
  e = error_of(base + "walls:\n  - {points: [[1, 1]]}\n");
  has(e, "walls[0].points");
  e = error_of(base + "boxes:\n  - {centre: [2, 2], size: [0.2, 0.2], z_m: [1.0, 0.5]}\n");
  has(e, "boxes[0].z_m");
  has(e, "z_max must be above z_min");
  e = error_of(base + "polygons:\n  - {points: [[2, 1], [3, 2], [3, 1], [2, 2.5]]}\n");
  has(e, "not simple");
  e = error_of(base + "boxes:\n  - {centre: [0.5, 0.5], size: [0.5, 0.5]}\n");
  has(e, "start");
  has(e, "inside");
  e = error_of("name: x\nfloor: {min: [0, 0], max: [0, 3]}\nstart: [0, 1, 0]\n");
  has(e, "floor");
  e = error_of("name: x\nfloor: {min: [0, 0], max: [4, 3]}\n");
  has(e, "start");
  has(e, "required key is missing");
  e = error_of(base + "boxes:\n  - {centre: [3, 2], size: [0.5, \"a\"]}\n");
  has(e, "boxes[0].size[1]");
  e = error_of(base + "boxes:\n  - {centre: [3, 2], size: [0.5, 0.5], surface: {texture: marble}}\n");
  has(e, "boxes[0].surface.texture");
  e = error_of("name: [unclosed\n");
  has(e, "not valid YAML");
  e = error_of(base + "flor: 1\n");
  has(e, "did you mean 'floor'");
  // Files: the path is in the message.
  TempDir dir;
  try {
    (void)duet::sim::load_world(dir / "missing.yaml");
    ADD_FAILURE();
  } catch (const duet::Error& err) {
    has(err.what(), "missing.yaml");
  }
  const fs::path bad = dir.write("bad_world.yaml", base + "walls: 3\n");
  try {
    (void)duet::sim::load_world(bad);
    ADD_FAILURE();
  } catch (const duet::Error& err) {
    has(err.what(), "bad_world.yaml");
    has(err.what(), "walls");
  }
  EXPECT_THROW((void)duet::sim::builtin_world("moon"), duet::Error);
  EXPECT_THROW((void)duet::sim::resolve_world("no/such/world.yaml"), duet::Error);
}

TEST(SimWorld, WallsPolylinesAndClockwisePolygons) {
  World w = load_text(R"(name: walls
floor: {min: [0, 0], max: [4, 3]}
start: [2, 1.5, 0]
walls:
  - {points: [[0.5, 0.5], [3.5, 0.5], [3.5, 2.5]], thickness_m: 0.2, height_m: 1.5}
polygons:
  - {points: [[1, 2], [1, 2.5], [1.5, 2.5], [1.5, 2]]}
)");
  ASSERT_EQ(w.solids.size(), 3u);  // two wall segments and the polygon
  EXPECT_FLOAT_EQ(w.solids[0].z_max_m, 1.5f);
  // Clockwise input is made counter-clockwise.
  const auto& p = w.solids[2].polygon;
  double area = 0;
  for (std::size_t i = 0; i < p.size(); ++i) area += p[i].x() * p[(i + 1) % p.size()].y() - p[(i + 1) % p.size()].x() * p[i].y();
  EXPECT_GT(area, 0.0);
  // The wall corner is closed (ends extended by half the thickness).
  EXPECT_TRUE(duet::sim::collides(w, {3.55f, 0.45f}, 0.0f));
  EXPECT_NEAR(duet::sim::clearance(w, {2.0f, 1.0f}), 0.4f, 1e-5f);
}

// A 40 x 30 map at 0.1 m: a closed room - free from (-0.7, -0.2) to (2.6, 2.1) - with one inner
// block at (0.5..0.9, 0.5..0.8), unknown outside.
fs::path write_room(const TempDir& dir) {
  duet::OccupancyGrid grid(0.1f, Eigen::Vector2f(-1.0f, -0.5f), 40, 30);
  for (int y = 0; y < 30; ++y)
    for (int x = 0; x < 40; ++x) {
      float l = duet::OccupancyGrid::kUnknown;
      if (x >= 2 && x <= 37 && y >= 2 && y <= 27) l = (x == 2 || x == 37 || y == 2 || y == 27) ? 3.0f : -2.0f;
      if (x >= 15 && x <= 18 && y >= 10 && y <= 12) l = 3.0f;
      grid.logodds()[grid.index(x, y)] = l;
    }
  duet::write_map_server(grid, dir / "room.yaml");
  return dir / "room.yaml";
}

TEST(SimWorldMap, ExtrudesOccupiedCellsOfAMapServerMap) {
  TempDir dir;
  write_room(dir);
  const duet::OccupancyGrid grid = duet::read_map_server(dir / "room.yaml");
  const World w = duet::sim::load_world(dir / "room.yaml");  // dispatches on the map keys
  EXPECT_EQ(w.name, "room");
  EXPECT_NEAR(w.floor.min.x(), -1.0f, 1e-6f);
  EXPECT_NEAR(w.floor.max.y(), 2.5f, 1e-5f);
  const auto truth = duet::sim::rasterize(w, 0.1f, 0.0f, 0.6f);
  ASSERT_EQ(truth.width, 40);
  ASSERT_EQ(truth.height, 30);
  for (int y = 0; y < 30; ++y)
    for (int x = 0; x < 40; ++x) {
      const float l = grid.at(x, y);
      const bool is_free = std::isfinite(l) && l < 0.0f;
      // Free cells stay free; solid cells next to free space (within 2) are walls.
      if (is_free) {
        EXPECT_EQ(truth.at(x, y), 0) << x << "," << y;
      }
      bool near_free = false;
      for (int dy = -2; dy <= 2; ++dy)
        for (int dx = -2; dx <= 2; ++dx) {
          const int xx = x + dx, yy = y + dy;
          if (xx >= 0 && yy >= 0 && xx < 40 && yy < 30 && std::isfinite(grid.at(xx, yy)) && grid.at(xx, yy) < 0.0f) near_free = true;
        }
      if (!is_free && near_free) {
        EXPECT_EQ(truth.at(x, y), 1) << x << "," << y;
      }
    }
  // The start is free, with room for the robot.
  EXPECT_FALSE(duet::sim::collides(w, {w.start.x, w.start.y}, 0.3f));
  // Rectangles were merged: far fewer solids than wall cells.
  EXPECT_LT(w.solids.size(), 40u);
  // A map with no free cell is an error naming the file.
  duet::OccupancyGrid solid(0.1f, Eigen::Vector2f::Zero(), 5, 5);
  for (float& l : solid.logodds()) l = 3.0f;
  duet::write_map_server(solid, dir / "solid.yaml");
  try {
    (void)duet::sim::world_from_map(dir / "solid.yaml");
    ADD_FAILURE();
  } catch (const duet::Error& e) {
    EXPECT_NE(std::string(e.what()).find("solid.yaml"), std::string::npos) << e.what();
  }
}

TEST(SimWorldMap, WillowGarageOfficeBecomesAWorld) {
  const fs::path map = fs::path(DUET_DATA_DIR) / "maps" / "willow-2010-02-18-0.10.yaml";
  if (!fs::exists(map)) GTEST_SKIP() << "data absent: " << map;
  const World w = duet::sim::world_from_map(map);
  EXPECT_GT(w.solids.size(), 100u);
  EXPECT_FALSE(duet::sim::collides(w, {w.start.x, w.start.y}, 0.3f));
  const auto truth = duet::sim::rasterize(w, 0.1f);
  const auto mask = duet::sim::reachable_free_mask(truth, w.start, 0.2f, 5.0f);
  std::size_t reach = 0;
  for (const auto m : mask) reach += m;
  // An office floor: hundreds of square metres reachable.
  EXPECT_GT(static_cast<double>(reach) * 0.01, 200.0);
}

template <class F>
std::string error_of(F&& f) {
  try {
    f();
  } catch (const duet::Error& e) {
    return e.what();
  }
  return "no error";
}

// A map's NAME.start beside its YAML is where the robot starts (the real robot's first pose);
// without one - or with start_file off - the computed start; bad files are named errors.
TEST(SimWorldMap, AStartFileBesideTheMapIsWhereTheRobotStarts) {
  TempDir dir;
  const fs::path map = write_room(dir);
  const World computed = duet::sim::world_from_map(map);
  duet::write_text_file(dir / "room.start", "# x y theta\n2.0 1.5 0.75\n");
  const World w = duet::sim::load_world(map);
  EXPECT_FLOAT_EQ(w.start.x, 2.0f);
  EXPECT_FLOAT_EQ(w.start.y, 1.5f);
  EXPECT_FLOAT_EQ(w.start.theta, 0.75f);
  duet::sim::MapWorldOptions no_file;
  no_file.start_file = false;
  const World w2 = duet::sim::world_from_map(map, no_file);
  EXPECT_EQ(w2.start.x, computed.start.x);
  EXPECT_EQ(w2.start.y, computed.start.y);
  const auto expect_error = [&](const std::string& text, const std::string& want) {
    duet::write_text_file(dir / "room.start", text);
    const std::string e = error_of([&] { (void)duet::sim::load_world(map); });
    EXPECT_NE(e.find("room.start"), std::string::npos) << e;
    EXPECT_NE(e.find(want), std::string::npos) << "for '" << text << "': " << e;
  };
  expect_error("", "no pose");
  expect_error("1.0 2.0\n", "expected 3 numbers");
  expect_error("1.0 two 0.5\n", "y is not a number: 'two'");
  expect_error("1.0 1.0 nan\n", "theta must be finite");
  expect_error("1.0 1.0 0\n1.0 1.0 0\n", ":2: a second pose");
  // The centre inside the block: validate() names it.
  duet::write_text_file(dir / "room.start", "0.7 0.65 0\n");
  EXPECT_NE(error_of([&] { (void)duet::sim::load_world(map); }).find("inside"), std::string::npos);
}

TEST(SimWorldStart, ParseStartTakesXYThetaAndNamesWhatIsWrong) {
  const duet::Pose2 p = duet::sim::parse_start("1.5, -2,0.25");
  EXPECT_FLOAT_EQ(p.x, 1.5f);
  EXPECT_FLOAT_EQ(p.y, -2.0f);
  EXPECT_FLOAT_EQ(p.theta, 0.25f);
  EXPECT_NEAR(duet::sim::parse_start("0,0,7").theta, 7.0f - 2.0f * 3.14159265f, 1e-5f);  // wrapped
  EXPECT_NE(error_of([] { (void)duet::sim::parse_start("1,2"); }).find("expected 3 numbers"), std::string::npos);
  EXPECT_NE(error_of([] { (void)duet::sim::parse_start("1,2,3,4"); }).find("got 4"), std::string::npos);
  EXPECT_NE(error_of([] { (void)duet::sim::parse_start("1,,3"); }).find("y is not a number"), std::string::npos);
  EXPECT_NE(error_of([] { (void)duet::sim::parse_start("1x,2,3"); }).find("x is not a number: '1x'"), std::string::npos);
  EXPECT_NE(error_of([] { (void)duet::sim::parse_start("inf,2,3"); }).find("x must be finite"), std::string::npos);
  EXPECT_NE(error_of([] { (void)duet::sim::parse_start(""); }).find("start ''"), std::string::npos);
}

// set_start: a robot of the given radius must stand there - on the floor, clear of every solid;
// the error names the pose and the solid, and leaves the world as it was.
TEST(SimWorldStart, SetStartChecksThatTheRobotStandsThere) {
  TempDir dir;
  World w = duet::sim::load_world(write_room(dir));
  const duet::Pose2 before = w.start;
  const auto rejected = [&](duet::Pose2 p, const std::string& want) {
    const std::string e = error_of([&] { duet::sim::set_start(w, p, 0.2f, "--start"); });
    EXPECT_NE(e.find("--start (" ), std::string::npos) << e;
    EXPECT_NE(e.find(want), std::string::npos) << e;
    EXPECT_EQ(w.start.x, before.x);
    EXPECT_EQ(w.start.y, before.y);
  };
  rejected({0.7f, 0.65f, 0.0f}, "overlaps");          // the block's middle
  rejected({1.05f, 0.65f, 0.0f}, "radius 0.2 m");     // 0.15 m beside the block: the robot's edge is in it
  rejected({-0.65f, 1.0f, 0.0f}, "overlaps");         // against the west wall
  rejected({50.0f, 1.0f, 0.0f}, "off the floor");
  rejected({1.0f, NAN, 0.0f}, "not a finite pose");
  duet::sim::set_start(w, {2.0f, 1.5f, 1.0f}, 0.2f, "--start");
  EXPECT_EQ(w.start.x, 2.0f);
  EXPECT_EQ(w.start.theta, 1.0f);
}

// The five real buildings' start files (the real robots' first poses): each is read, and a robot
// of the dual profile's radius stands clear there.
TEST(SimWorldMap, TheRealBuildingsStartWhereTheirRobotsDid) {
  int seen = 0;
  for (const char* name : {"freiburg-101", "orebro", "belgioioso", "fhw", "edmonton"}) {
    const fs::path map = fs::path(DUET_DATA_DIR) / "maps" / (std::string(name) + ".yaml");
    if (!fs::exists(map)) continue;
    ++seen;
    World w = duet::sim::world_from_map(map);
    const duet::Pose2 file = duet::sim::read_start_file(fs::path(DUET_DATA_DIR) / "maps" / (std::string(name) + ".start"));
    EXPECT_EQ(w.start.x, file.x) << name;
    EXPECT_EQ(w.start.y, file.y) << name;
    EXPECT_NO_THROW(duet::sim::set_start(w, w.start, 0.177f, name)) << name;
  }
  if (seen == 0) GTEST_SKIP() << "data absent: " << DUET_DATA_DIR;
}

TEST(SimWorld, TooLargeAFloorNamesTheWorldFile) {
  // It said "rasterize: the floor is too large" without the file.
  const duet::sim::World w = duet::sim::parse_world(
      "name: big\nfloor: {min: [0, 0], max: [9000, 9000]}\nstart: [1.0, 1.0, 0.0]\n", "my/big.yaml");
  try {
    (void)duet::sim::rasterize(w, 0.05f);
    FAIL() << "no error";
  } catch (const duet::Error& e) {
    EXPECT_EQ(e.code(), duet::ErrorCode::kOutOfRange);
    EXPECT_NE(std::string(e.what()).find("my/big.yaml: world 'big': the floor (9000 x 9000 m) is too large"), std::string::npos)
        << e.what();
  }
}
