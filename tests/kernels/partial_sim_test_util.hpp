#pragma once
// Helpers shared by the tests of Procedure 1 (test_partial_sim.cpp) and of the combined strategy
// of Fig. 6 (test_exploration_decision.cpp): hand-made grids at 0.05 m and their prepared models.
#include <duet/kernels/exploration.hpp>
#include <duet/kernels/partial_sim.hpp>

#include <cstddef>
#include <limits>
#include <vector>

namespace duet {
namespace test_partial_sim {

inline constexpr float kFreeL = -2.0f;  // clamped free (GridUpdateSettings.min_logodds)
inline constexpr float kOccL = 3.5f;    // clamped occupied
inline const float kUnknown = std::numeric_limits<float>::quiet_NaN();

// A w x h grid at 0.05 m, all unknown, origin (0, 0).
struct TestGrid {
  int w, h;
  float res = 0.05f;
  std::vector<float> l;
  TestGrid(int w_, int h_) : w(w_), h(h_), l(static_cast<std::size_t>(w_) * static_cast<std::size_t>(h_), kUnknown) {}
  float& at(int x, int y) { return l[static_cast<std::size_t>(y) * static_cast<std::size_t>(w) + static_cast<std::size_t>(x)]; }
  void fill(int x0, int y0, int x1, int y1, float v) {  // [x0, x1) x [y0, y1)
    for (int y = y0; y < y1; ++y)
      for (int x = x0; x < x1; ++x) at(x, y) = v;
  }
  // A room: free interior [x0, x1) x [y0, y1), walls one cell thick around it.
  void room(int x0, int y0, int x1, int y1) {
    fill(x0 - 1, y0 - 1, x1 + 1, y1 + 1, kOccL);
    fill(x0, y0, x1, y1, kFreeL);
  }
  [[nodiscard]] GridView view() const { return GridView(l, w, h, res, Eigen::Vector2f(0.0f, 0.0f)); }
};

struct Prepared {
  ObservationModel model;
  InflatedGrid inflated;
  explicit Prepared(const TestGrid& g, ObservationBackend backend = ObservationBackend::kDda)
      : model([&] {
          ObservationSettings os;
          os.backend = backend;
          return os;
        }()) {
    model.set_grid(g.view());
    inflate(g.view(), InflationSettings{}, inflated);
  }
};

// 10 m x 10 m world: a 4 m x 4 m known room at [1, 5) x [3, 7) m with a door (1 m) in its east
// wall leading to the unknown; the robot in the west half, facing west (both sensors see walls).
inline TestGrid door_room() {
  TestGrid g(200, 200);
  g.room(20, 60, 100, 140);
  for (int y = 90; y < 110; ++y) g.at(100, y) = kFreeL;  // the door: free cells in the east wall
  return g;
}

}  // namespace test_partial_sim
}  // namespace duet
