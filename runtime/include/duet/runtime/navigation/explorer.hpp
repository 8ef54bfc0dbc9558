#pragma once
/// @file explorer.hpp
/// The explorer of the paper (§3, Fig. 6) on one thread: a Navigator (navigator.hpp: costmaps,
/// goal life cycle, global path) and a Controller (controller.hpp: the dynamic window and its
/// behaviours) linked directly - a decision the controller asks for is taken at once, in the
/// same control period. This is what lockstep simulation, tests and single-threaded embedding
/// use; the runtime's background mode runs the same two parts on two threads
/// (exploration_runtime.hpp).
///
/// Frames: all poses in the map frame (the frame of the grid given to update_map()).
/// Thread safety: not thread-safe (one call at a time); the kernels run TBB-parallel in the
/// caller's task arena, and results do not depend on the thread count.
#include <duet/runtime/navigation/controller.hpp>
#include <duet/runtime/navigation/navigator.hpp>

namespace duet {

class Explorer {
 public:
  /// `profile.exploration` configures the kernels; its sensors give the observation sectors.
  explicit Explorer(const Profile& profile, const ExplorerSettings& settings = {});

  /// The latest map (1 Hz): rebuilds the costmaps, re-plans the current goal's path.
  void update_map(const OccupancyGrid& grid, const Pose2& robot, double now_s) { navigator_.update_map(grid, robot, now_s); }
  /// The recent obstacle points (map frame), used from the next update_map() on.
  void set_recent_obstacles(std::span<const Eigen::Vector2f> points) { navigator_.set_recent_obstacles(points); }
  /// The map frame moved by D (new = D * old): what the explorer keeps in it moves too.
  void shift_frame(const Pose2& D);
  /// One control period (20 Hz): a decision if needed, then the dynamic window's command.
  Twist control(const Pose2& robot, const Twist& current, double now_s);

  [[nodiscard]] ExplorerState state() const noexcept { return navigator_.state(); }
  /// Why exploration stopped (kDone): the last decision's status.
  [[nodiscard]] ExplorationStatus stop_status() const noexcept { return navigator_.stop_status(); }
  /// Why exploration stopped, in words (Navigator::stop_detail()).
  [[nodiscard]] const std::string& stop_detail() const noexcept { return navigator_.stop_detail(); }
  /// What was left unexplored, where and why (Navigator::left_unexplored()).
  [[nodiscard]] const std::vector<UnexploredRegion>& left_unexplored() const noexcept { return navigator_.left_unexplored(); }
  /// The navigator's and the controller's counters together.
  [[nodiscard]] ExplorerStats stats() const;
  [[nodiscard]] const std::optional<Pose2>& goal() const noexcept { return navigator_.goal(); }
  [[nodiscard]] const std::vector<Eigen::Vector2f>& path() const noexcept { return navigator_.path(); }
  [[nodiscard]] const InflatedGrid& inflated() const noexcept { return navigator_.inflated(); }
  [[nodiscard]] const InflatedGrid& planning_grid() const noexcept { return navigator_.planning_grid(); }
  [[nodiscard]] const std::vector<Eigen::Vector2f>& contacts() const noexcept { return navigator_.contacts(); }
  [[nodiscard]] const std::vector<Eigen::Vector2f>& recent_obstacles() const noexcept { return navigator_.recent_obstacles(); }
  [[nodiscard]] const InflatedGrid& local_grid() const noexcept { return navigator_.local_grid(); }
  [[nodiscard]] const ExplorationDecision& last_decision() const noexcept { return navigator_.last_decision(); }
  [[nodiscard]] const std::vector<DecisionRecord>& decisions() const noexcept { return navigator_.decisions(); }
  [[nodiscard]] const std::vector<Eigen::Vector2f>& frontier_points() const noexcept { return navigator_.frontier_points(); }

  [[nodiscard]] Navigator& navigator() noexcept { return navigator_; }
  [[nodiscard]] const Navigator& navigator() const noexcept { return navigator_; }
  [[nodiscard]] Controller& controller() noexcept { return controller_; }
  [[nodiscard]] const Controller& controller() const noexcept { return controller_; }

 private:
  Navigator navigator_;
  Controller controller_;
};

/// The navigator's counters with the controller's.
[[nodiscard]] ExplorerStats merge_stats(ExplorerStats navigator, const ControllerStats& controller);

}  // namespace duet
