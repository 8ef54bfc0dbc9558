// The combined strategy of Fig. 6 (see exploration.hpp).
#include <duet/kernels/error.hpp>
#include <duet/kernels/exploration.hpp>

#include <tbb/task_group.h>

#include <cmath>
#include <exception>
#include <optional>
#include <string>

namespace duet {

void validate(const ExplorationSettings& s) {
  validate(s.simulation);
  validate(s.frontier);
  if (!std::isfinite(s.eps_r_bits) || s.eps_r_bits < 0.0f)
    fail(ErrorCode::kInvalidArgument,
         "ExplorationSettings.eps_r_bits = " + std::to_string(s.eps_r_bits) + " is outside [0, inf)");
}

const char* to_string(ExplorationStatus s) {
  switch (s) {
    case ExplorationStatus::kSimulatedGoal: return "simulated_goal";
    case ExplorationStatus::kFrontierGoal: return "frontier_goal";
    case ExplorationStatus::kNoFrontier: return "no_frontier";
    case ExplorationStatus::kAllUnreachable: return "all_frontiers_unreachable";
    case ExplorationStatus::kAllBlacklisted: return "all_frontiers_blacklisted";
    case ExplorationStatus::kRobotBlocked: return "robot_blocked";
  }
  return "unknown";
}

Pose2 frontier_goal_pose(const FrontierResult& f, const Pose2& robot) {
  Pose2 g{f.goal_xy.x(), f.goal_xy.y(), 0.0f};
  const auto& path = f.path;
  const Eigen::Vector2f look = f.target_xy - f.goal_xy;
  if (look.squaredNorm() > 0.0f) {  // an approach cell: face the frontier cell it is for
    g.theta = std::atan2(look.y(), look.x());
  } else if (path.size() >= 2) {
    const Eigen::Vector2f dir = path.back() - path[path.size() - 2];
    g.theta = std::atan2(dir.y(), dir.x());
  } else {
    g.theta = std::atan2(g.y - robot.y, g.x - robot.x);
  }
  return g;
}

ExplorationDecision decide_goal(const ObservationModel& model, const InflatedGrid& inflated, const Pose2& robot,
                                std::span<const SensorSector> sensors, const GoalBlacklist& blacklist,
                                double now_s, const ExplorationSettings& s, ExplorationWorkspace& ws) {
  validate(s);
  ExplorationDecision d;
  d.goal = robot;
  // With simulation, the frontier search (which reads only the inflated grid, the blacklist and
  // its own workspace) runs as a concurrent task while Procedure 1 runs, so that a second thread
  // is never idle during the simulation's serial parts and the fall-back costs no extra latency.
  // Its result is used exactly as if it ran afterwards: only when the simulated goal is not
  // taken (and discarded otherwise), so the decision is the same as the sequential one.
  std::optional<FrontierResult> speculative;
  std::exception_ptr speculative_error;
  if (s.use_simulation) {
    tbb::task_group tg;
    if (s.concurrent_frontier_search)
      tg.run([&] {
        try {
          speculative = find_frontier(inflated, Eigen::Vector2f(robot.x, robot.y), blacklist, now_s, s.frontier, ws.frontier);
        } catch (...) {
          speculative_error = std::current_exception();  // rethrown only if the search's result is needed
        }
      });
    try {
      d.simulation = partial_map_simulation(model, inflated, robot, sensors, s.simulation, ws.simulation);
    } catch (...) {
      tg.wait();  // never leave the task running on the caller's data
      throw;
    }
    tg.wait();
    d.reward_bits = d.simulation.reward_bits;
    // Fig. 6: R_g > eps_R (or only R_g's part from unknown cells, eps_r_unknown_only).
    const float tested = s.eps_r_unknown_only ? d.simulation.unknown_reward_bits : d.simulation.reward_bits;
    if (d.simulation.found && tested > s.eps_r_bits) {
      const Eigen::Vector2f g(d.simulation.goal.x, d.simulation.goal.y);
      if (!blacklist.blocks(g, s.frontier.blacklist_radius_m, now_s)) {
        d.status = ExplorationStatus::kSimulatedGoal;
        d.goal = d.simulation.goal;
        if (speculative) {  // it ran anyway: keep it for the caller (a failed search is simply not kept)
          d.frontier = std::move(*speculative);
          d.frontier_searched = true;
        }
        return d;
      }
      d.simulated_goal_blacklisted = true;
    }
  }
  // Otherwise the global frontier search (§3.2).
  if (speculative_error) std::rethrow_exception(speculative_error);
  d.frontier = speculative ? std::move(*speculative)
                           : find_frontier(inflated, Eigen::Vector2f(robot.x, robot.y), blacklist, now_s, s.frontier, ws.frontier);
  d.frontier_searched = true;
  switch (d.frontier.status) {
    case FrontierStatus::kFound: {
      d.status = ExplorationStatus::kFrontierGoal;
      d.goal = frontier_goal_pose(d.frontier, robot);
      break;
    }
    case FrontierStatus::kNoFrontier: d.status = ExplorationStatus::kNoFrontier; break;
    case FrontierStatus::kAllUnreachable: d.status = ExplorationStatus::kAllUnreachable; break;
    case FrontierStatus::kAllBlacklisted: d.status = ExplorationStatus::kAllBlacklisted; break;
    case FrontierStatus::kRobotBlocked: d.status = ExplorationStatus::kRobotBlocked; break;
  }
  return d;
}

}  // namespace duet
