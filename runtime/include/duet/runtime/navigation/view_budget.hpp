#pragma once
/// @file view_budget.hpp
/// The budget of the looking (view goals): once every frontier left is unreachable, the robot
/// looks at them from view goals, and keeps looking only while the map grows. A phase of looking
/// only begins a window at its first decision; at each decision that looks once
/// view_gain_window_s have passed since the window began, the known area added since is set
/// against view_min_gain_m2: less, and the budget is spent; as much or more, and a new window
/// begins there. A decision with a reachable frontier ends the phase (the next look begins a
/// fresh window) and renews a spent budget.
/// Why a frontier phase ends the window: keeping it across them (their gain counted within it)
/// changed no run measured - the long tails gain more than 5 m^2 per window either way
/// (bench/RESULTS.md, "Stop 57").
#include <cstddef>
#include <string>

namespace duet {

class ViewBudget {
 public:
  /// min_gain_m2 <= 0: no budget (always allows). window_s > 0.
  ViewBudget(float min_gain_m2, float window_s) : min_gain_m2_(min_gain_m2), window_s_(window_s) {}

  /// Whether allows(now_s, ...) reads known_cells (a window begins or is judged then); when not,
  /// the caller may pass 0 and spare counting the map.
  [[nodiscard]] bool counts_at(double now_s) const;
  /// A decision that would look, at now_s, with known_cells cells of cell_m2 known in the map.
  /// false: the budget is spent (note() says why).
  bool allows(double now_s, std::size_t known_cells, double cell_m2);
  /// A decision with a reachable frontier (or none at all): the phase of looking only is over.
  void frontier_reachable();
  /// Empty while the budget is not spent.
  [[nodiscard]] const std::string& note() const { return note_; }
  /// Whether a window is running (a phase of looking only).
  [[nodiscard]] bool in_window() const { return window_start_s_ >= 0.0; }

 private:
  float min_gain_m2_;
  float window_s_;
  double window_start_s_ = -1.0;  ///< -1: no window yet
  std::size_t window_known_ = 0;  ///< known cells when the window began
  std::string note_;
};

}  // namespace duet
