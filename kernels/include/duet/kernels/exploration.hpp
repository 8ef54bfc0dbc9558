#pragma once
/// @file exploration.hpp
/// The combined exploration strategy of the paper (§3.2, Fig. 6): the partial map simulation
/// (Procedure 1, partial_sim.hpp) proposes a goal X_g with reward R_g; if R_g > eps_R that goal is
/// taken, otherwise the global frontier search (frontier.hpp) gives the nearest reachable frontier;
/// otherwise the decision says why nothing is left.
///
/// Thread safety: decide_goal() reads the model, the inflated grid and the blacklist (nobody may
/// write them meanwhile) and needs exclusive use of its workspace. It may run the frontier search
/// as a TBB task concurrently with the simulation (ExplorationSettings::concurrent_frontier_search),
/// in the caller's task arena; both are deterministic, so the decision does not depend on it.
#include <duet/kernels/frontier.hpp>
#include <duet/kernels/inflation.hpp>
#include <duet/kernels/observation.hpp>
#include <duet/kernels/partial_sim.hpp>

#include <span>

namespace duet {

struct ExplorationSettings {
  PartialSimSettings simulation;
  FrontierSettings frontier;
  /// eps_R of Fig. 6 [bits]: the simulated goal is taken only if its expected entropy reduction
  /// exceeds this. One first observation of an unknown cell removes 0.03 bits (miss, l = -0.4)
  /// to 0.12 bits (hit, l = 0.85), so 1 bit is about 30 newly seen cells (0.075 m^2 at 0.05 m);
  /// but R_g also counts cells seen again (a free cell at l = -0.4 seen once more: 0.08 bits), so
  /// on a map of cells seen only a few times R_g is tens to hundreds of bits wherever the robot
  /// goes (eps_r_unknown_only below). [0, inf)
  float eps_r_bits = 1.0f;
  /// true: the test R_g > eps_R counts only the part of R_g from cells whose state is unknown
  /// (PartialSimResult::unknown_reward_bits), so a goal that would only confirm known cells -
  /// a cell seen free once is at l = -0.4, and seeing it again removes 0.08 bits, more than a
  /// first look at an unknown cell - does not keep the robot in rooms it has seen while the
  /// frontier search would lead on. false: the paper's test on the whole R_g.
  bool eps_r_unknown_only = false;
  /// false: frontier search only (the explore_lite-like baseline the benchmarks compare against).
  bool use_simulation = true;
  /// true: the frontier search runs concurrently with the simulation (a TBB task) and its result
  /// is used only if the simulated goal is not taken - the same decision as running it afterwards,
  /// with less latency on 2+ threads but ~1 ms of CPU wasted per decision when the simulated goal
  /// wins. false: the search runs only when needed, after the simulation (least CPU).
  bool concurrent_frontier_search = true;
};
void validate(const ExplorationSettings& s);

enum class ExplorationStatus {
  kSimulatedGoal,    ///< R_g > eps_R: the goal of the partial map simulation
  kFrontierGoal,     ///< the nearest reachable, non-blacklisted frontier
  kNoFrontier,       ///< nothing left: no frontier cell in the grid (exploration complete)
  kAllUnreachable,   ///< frontiers exist but none can be reached from the robot
  kAllBlacklisted,   ///< every reachable frontier is blacklisted (failed before) or too near
  kRobotBlocked,     ///< no traversable cell near the robot (it sits in an inflated obstacle)
};
[[nodiscard]] const char* to_string(ExplorationStatus s);

struct ExplorationDecision {
  ExplorationStatus status = ExplorationStatus::kNoFrontier;
  Pose2 goal;                 ///< valid for kSimulatedGoal and kFrontierGoal
  float reward_bits = 0.0f;   ///< R_g of the simulation (also reported when the frontier goal was taken)
  bool simulated_goal_blacklisted = false;  ///< R_g > eps_R but X_g lies in a blacklisted area
  PartialSimResult simulation;  ///< empty when use_simulation is false
  FrontierResult frontier;      ///< filled when the frontier search ran (see frontier_searched)
  /// The frontier search ran: always for a decision that is not kSimulatedGoal; also for a
  /// kSimulatedGoal with concurrent_frontier_search (the speculative result is kept, so a caller
  /// that also wants the frontiers - e.g. to stop when none is reachable - need not search again).
  bool frontier_searched = false;
  [[nodiscard]] bool has_goal() const noexcept {
    return status == ExplorationStatus::kSimulatedGoal || status == ExplorationStatus::kFrontierGoal;
  }
};

struct ExplorationWorkspace {
  PartialSimWorkspace simulation;
  FrontierWorkspace frontier;
};

/// The goal pose of a found frontier search (status kFound): at goal_xy, facing target_xy for an
/// approach cell, else along the last segment of the path (towards the unknown side), else (a
/// one-cell path) away from the robot.
[[nodiscard]] Pose2 frontier_goal_pose(const FrontierResult& f, const Pose2& robot);

/// One decision (Fig. 6). `model` and `inflated` describe the same grid; `now_s` is the caller's
/// clock for the blacklist's expiry. A frontier goal's pose is frontier_goal_pose().
ExplorationDecision decide_goal(const ObservationModel& model, const InflatedGrid& inflated, const Pose2& robot,
                                std::span<const SensorSector> sensors, const GoalBlacklist& blacklist,
                                double now_s, const ExplorationSettings& settings, ExplorationWorkspace& workspace);

}  // namespace duet
