#pragma once
/// @file view_goal.hpp
/// A view goal: when every frontier left is unreachable (or blacklisted), a cell the robot can
/// stand on and reach from which a frontier cell it cannot reach is seen - along a line of
/// sight through known-free cells, between view_min_range_m and view_range_m - for a first look
/// the least path length less view_frontier_weight x the length of the cell's frontier (a long
/// frontier is a large unseen region), for a look again the nearest by path. The goal faces the
/// frontier cell. A place (a frontier cell and what lies within the blacklist radius of it)
/// whose view goal was reached or abandoned is looked at again only when no place not yet looked
/// at is left, at least view_relook_after_s after its last look, and at most view_looks times in
/// all (a door shut at the first look may be open at the next).
/// The looking has a budget (ExplorerSettings::view_min_gain_m2, see view_budget.hpp): once a
/// window of view_gain_window_s spent only looking added less known area than that, no more
/// view goals until a reachable frontier turns up again.
#include <duet/runtime/navigation/goal_strategy.hpp>
#include <duet/runtime/navigation/view_budget.hpp>

namespace duet {

class ViewGoal final : public GoalStrategy {
 public:
  ViewGoal(const Profile& profile, const ExplorerSettings& settings);
  [[nodiscard]] std::string_view name() const override { return "view"; }
  std::optional<GoalProposal> propose(GoalQuery& q) override;
  void goal_ended(const GoalEnd& end) override;
  void shift(const Pose2& D) override;
  [[nodiscard]] std::vector<Eigen::Vector2f> looked_at() const override;
  [[nodiscard]] std::string stop_note() const override { return budget_.note(); }
  void map_updated(const GridView& latest, bool active) override;

 private:
  FrontierSettings frontier_;
  ExplorerSettings settings_;
  struct Look {
    Eigen::Vector2f xy;  ///< the frontier cell looked at (map frame)
    int count = 0;       ///< view goals for it that ended
    double last_s = 0.0; ///< when the last one ended
  };
  [[nodiscard]] const Look* look_near(const Eigen::Vector2f& p) const;
  std::vector<Look> looks_;
  CellThresholds cells_;
  double dwell_until_s_ = -1.0;  ///< after a look again: no view goal before this (the robot looks on)
  double dwell_max_s_ = -1.0;    ///< ... and never after this
  std::size_t dwell_free_ = 0;   ///< free cells around the target at the last map update
  bool dwell_changed_ = false;   ///< the last map update added free cells around the target
  Eigen::Vector2f target_{0.0f, 0.0f};
  FrontierWorkspace ws_;
  ViewBudget budget_;
};

}  // namespace duet
