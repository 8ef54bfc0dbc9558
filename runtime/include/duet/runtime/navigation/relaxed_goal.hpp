#pragma once
/// @file relaxed_goal.hpp
/// The frontier search on a relaxed grid, when the decision found every frontier unreachable,
/// the robot blocked, or every frontier blacklisted: the map inflated by the chassis radius plus
/// squeeze_margin_m instead of the planning radius (through a door the inflation closes), and,
/// when the robot is boxed in (the search reached less than boxed_in_area_m2), with uncertain
/// cells not blocking too. From a large area only frontiers of large unknown regions
/// (squeeze_min_unknown_m2) qualify. While its goal is active the navigator plans on the relaxed
/// grid and the dynamic window uses the relaxed radius.
#include <duet/runtime/navigation/goal_strategy.hpp>

namespace duet {

class RelaxedFrontierGoal final : public GoalStrategy {
 public:
  RelaxedFrontierGoal(const Profile& profile, const ExplorerSettings& settings);
  [[nodiscard]] std::string_view name() const override { return "relaxed_frontier"; }
  std::optional<GoalProposal> propose(GoalQuery& q) override;
  void map_updated(const GridView& latest, bool active) override;
  [[nodiscard]] const InflatedGrid* planning_grid() const override { return &relaxed_; }
  [[nodiscard]] std::optional<float> robot_radius_m() const override { return radius_m_; }

 private:
  void build(const GridView& latest);

  InflationSettings inflation_;
  FrontierSettings frontier_;
  ExplorerSettings settings_;
  float radius_m_;  ///< min(planning radius, chassis radius + squeeze_margin_m)
  bool boxed_in_ = false;
  InflatedGrid relaxed_;
  FrontierWorkspace ws_;
};

}  // namespace duet
