/// @file view_budget.cpp
/// The budget of the looking (see view_budget.hpp).
#include <duet/runtime/navigation/view_budget.hpp>

#include <cstdio>

namespace duet {

bool ViewBudget::counts_at(double now_s) const {
  return min_gain_m2_ > 0.0f && note_.empty() && (window_start_s_ < 0.0 || now_s - window_start_s_ >= static_cast<double>(window_s_));
}

bool ViewBudget::allows(double now_s, std::size_t known_cells, double cell_m2) {
  if (!counts_at(now_s)) return !(min_gain_m2_ > 0.0f) || note_.empty();  // off, spent, or within the window
  if (window_start_s_ < 0.0) {  // a phase of looking only begins: so does a window
    window_start_s_ = now_s;
    window_known_ = known_cells;
    return true;
  }
  const double gain_m2 = (static_cast<double>(known_cells) - static_cast<double>(window_known_)) * cell_m2;
  if (gain_m2 < static_cast<double>(min_gain_m2_)) {
    char buf[200];
    std::snprintf(buf, sizeof buf, "looking at them from view goals added %.1f m^2 in the last %.0f s (view_min_gain_m2 %.1f)", gain_m2,
                  now_s - window_start_s_, static_cast<double>(min_gain_m2_));
    note_ = buf;
    return false;
  }
  window_start_s_ = now_s;
  window_known_ = known_cells;
  return true;
}

void ViewBudget::frontier_reachable() {
  note_.clear();
  window_start_s_ = -1.0;
}

}  // namespace duet
