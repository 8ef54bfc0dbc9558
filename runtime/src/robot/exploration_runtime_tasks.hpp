#pragma once
/// @file exploration_runtime_tasks.hpp
/// ExplorationRuntime's private parts for its background mode (Execution::kBackground): what
/// the control thread hands a task (MapInput), what a task hands back (Result), the controller's
/// events for the navigator (Event) and the controller's link to a navigator that runs in the
/// background (Link). Shared by exploration_runtime.cpp (the control thread) and
/// exploration_runtime_tasks.cpp (the tasks); not installed.
#include <duet/runtime/robot/exploration_runtime.hpp>

#include <algorithm>
#include <chrono>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace duet {

/// The steady clock in seconds (latencies and the frame-to-map time).
inline double runtime_wall_s() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

/// One controller -> navigator event (kBackground).
struct ExplorationRuntime::Event {
  enum class Kind { kTrail, kStall, kReached, kAbandon, kReturnHome, kStop } kind = Kind::kTrail;
  Eigen::Vector2f xy{0.0f, 0.0f};
  std::uint64_t goal_id = 0;
  AbandonReason why = AbandonReason::kTimeout;
  double t_s = 0.0;
  Pose2 robot{};     ///< kReturnHome: the pose estimate when asked
  std::string text;  ///< kStop: why
};

/// What a map update needs, taken on the control thread.
struct ExplorationRuntime::MapInput {
  std::vector<RgbdImage> images;  ///< one per sensor
  double t_frames = 0.0;          ///< the frames' mean stamp [s]
  Pose2 odom_at;                  ///< odometry interpolated to t_frames
  Pose2 odom_latest;              ///< the latest odometry when the update was asked for
  double now_s = 0.0;
  std::optional<Pose2> override_pose;
  bool odometry_confirmed = false;  ///< visual odometry's health was good (PoseCorrector::confirm_odometry)
  bool odometry_contradicted = false;  ///< a stall, or vision gated out a jump, since the last update (PoseCorrector::contradict_odometry)
};

/// What a background task hands to the control thread.
struct ExplorationRuntime::Result {
  bool map = false;                       ///< a map update (else a decision)
  std::shared_ptr<const NavSnapshot> nav;
  ExplorerStats nav_stats;
  std::shared_ptr<const OccupancyGrid> grid;
  Pose2 correction;
  float heading_rate = 0.0f;
  std::optional<Pose2> shift;
  std::vector<RgbdImage> images;          ///< to recycle on the control thread
  std::size_t scan_matches = 0, scan_match_rejected = 0, loop_closures = 0;
  std::size_t relocalizations = 0, relocalizations_held = 0, relocalizations_asked = 0, relocalizations_new_space = 0;
  std::size_t relocalizations_ambiguous = 0;
  std::size_t relocalizations_in_obstacle = 0;
  std::size_t relocalizations_at_edge = 0;
  Pose2 relocalization;
  RelocalizationScores relocalization_scores;
  float relocalization_conflict = 0.0f;
  double now_s = 0.0;
  double scan_match_time_s = 0.0;
  double frame_to_map_s = 0.0;
  double done_wall_s = 0.0;
};

/// The controller's link to the navigator in the background (kBackground): events are queued,
/// a decision is a task, and the plan is the latest published one with the goals the
/// controller gave up (and, after a stall, the goal) taken out until the navigator has seen it.
class ExplorationRuntime::Link final : public GoalLink {
 public:
  explicit Link(ExplorationRuntime& rt) : rt_(rt) {}
  NavPlanView plan() override {
    NavPlanView v = rt_.plan_ ? rt_.plan_->view() : NavPlanView{};
    if (v.goal && v.goal_id <= dropped_goal_id_) {
      v.goal = nullptr;
      v.path = {};
    }
    if (stall_pending_) v.wait_for_map = true;
    return v;
  }
  void trail(const Eigen::Vector2f& p) override { post({Event::Kind::kTrail, p, 0, AbandonReason::kTimeout, 0.0}); }
  void stall(const Eigen::Vector2f& contact, double now_s) override {
    if (rt_.plan_ && rt_.plan_->goal) dropped_goal_id_ = std::max(dropped_goal_id_, rt_.plan_->goal_id);
    stall_pending_ = true;
    post({Event::Kind::kStall, contact, 0, AbandonReason::kStuck, now_s});
  }
  void decide(const Pose2& robot, double now_s) override { rt_.submit_decision(robot, now_s); }
  void goal_reached(std::uint64_t id, double now_s) override {
    dropped_goal_id_ = std::max(dropped_goal_id_, id);
    post({Event::Kind::kReached, Eigen::Vector2f::Zero(), id, AbandonReason::kTimeout, now_s});
  }
  void abandon(std::uint64_t id, AbandonReason why, double now_s) override {
    dropped_goal_id_ = std::max(dropped_goal_id_, id);
    post({Event::Kind::kAbandon, Eigen::Vector2f::Zero(), id, why, now_s});
  }
  /// A map update that started after the stall was posted has been taken: the navigator knows.
  void map_seen() { stall_pending_ = false; }
  /// An operator's request: the current goal is no longer followed; the navigator hears of it
  /// at the start of its next task.
  void request(Event e) {
    if (rt_.plan_ && rt_.plan_->goal) dropped_goal_id_ = std::max(dropped_goal_id_, rt_.plan_->goal_id);
    post(std::move(e));
  }

 private:
  void post(const Event& e) {
    std::lock_guard<std::mutex> lock(rt_.inbox_mutex_);
    rt_.inbox_.push_back(e);
  }
  ExplorationRuntime& rt_;
  std::uint64_t dropped_goal_id_ = 0;
  bool stall_pending_ = false;
};

}  // namespace duet
