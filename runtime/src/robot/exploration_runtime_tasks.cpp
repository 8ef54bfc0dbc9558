/// @file exploration_runtime_tasks.cpp
/// ExplorationRuntime's background tasks (Execution::kBackground): a map update and a decision
/// run on the worker, hand their results back through results_, and the control thread takes
/// them at its next tick (see exploration_runtime.hpp, "Threads").
#include <duet/runtime/robot/background_worker.hpp>
#include <duet/runtime/robot/exploration_runtime.hpp>

#include "exploration_runtime_tasks.hpp"

#include <chrono>
#include <thread>

namespace duet {

void ExplorationRuntime::submit_map_update(MapInput&& input) {
  map_in_flight_ = true;
  const double submitted = runtime_wall_s();
  worker_->submit([this, in = std::make_shared<MapInput>(std::move(input)), submitted] {
    apply_events();
    Result r;
    r.map = true;
    r.shift = map_update(*in);
    r.nav = std::make_shared<const NavSnapshot>(explorer_.navigator().snapshot());
    r.nav_stats = explorer_.navigator().stats();
    r.grid = std::make_shared<const OccupancyGrid>(mapper_.grid());
    r.correction = corrector_.correction();
    r.heading_rate = corrector_.heading_rate();
    r.scan_matches = corrector_.matches();
    r.scan_match_rejected = corrector_.rejected();
    r.relocalizations_held = corrector_.relocalizations_held();
    r.relocalizations_new_space = corrector_.relocalizations_new_space();
    r.relocalizations_ambiguous = corrector_.relocalizations_ambiguous();
    r.relocalizations_in_obstacle = corrector_.relocalizations_in_obstacle();
    r.relocalizations_at_edge = corrector_.relocalizations_at_edge();
    r.relocalizations_asked = corrector_.relocalizations_asked();
    r.scan_match_time_s = corrector_.time_s();
    r.relocalizations = corrector_.relocalizations();
    r.relocalization = corrector_.last_relocalization();
    r.relocalization_scores = corrector_.last_relocalization_scores();
    r.relocalization_conflict = corrector_.last_conflict();
    r.now_s = in->now_s;
    r.images = std::move(in->images);
    r.done_wall_s = runtime_wall_s();
    r.frame_to_map_s = (in->now_s - in->t_frames) + (r.done_wall_s - submitted);
    std::lock_guard<std::mutex> lock(results_mutex_);
    results_.push_back(std::move(r));
  });
}

void ExplorationRuntime::apply_events() {
  std::vector<Event> events;
  {
    std::lock_guard<std::mutex> lock(inbox_mutex_);
    events.swap(inbox_);
  }
  Navigator& nav = explorer_.navigator();
  for (const Event& e : events) {
    switch (e.kind) {
      case Event::Kind::kTrail: nav.add_trail(e.xy); break;
      case Event::Kind::kStall: nav.stall(e.xy, e.t_s); break;
      case Event::Kind::kReached: nav.goal_reached(e.goal_id, e.t_s); break;
      case Event::Kind::kAbandon: nav.abandon(e.goal_id, e.why, e.t_s); break;
      case Event::Kind::kReturnHome: nav.return_home(e.robot, e.t_s); break;
      case Event::Kind::kStop: nav.stop(e.text); break;
    }
  }
}

void ExplorationRuntime::submit_decision(const Pose2& robot, double now_s) {
  if (decision_in_flight_) return;
  decision_in_flight_ = true;
  decision_asked_wall_ = runtime_wall_s();
  ++stats_.decisions_requested;
  worker_->submit([this, robot, now_s] {
    apply_events();
    const double w0 = runtime_wall_s();
    explorer_.navigator().decide(robot, now_s);
    if (settings_.decision_delay_s > 0.0) {
      const double left = settings_.decision_delay_s - (runtime_wall_s() - w0);
      if (left > 0.0) std::this_thread::sleep_for(std::chrono::duration<double>(left));
    }
    Result r;
    r.nav = std::make_shared<const NavSnapshot>(explorer_.navigator().snapshot());
    r.nav_stats = explorer_.navigator().stats();
    r.done_wall_s = runtime_wall_s();
    std::lock_guard<std::mutex> lock(results_mutex_);
    results_.push_back(std::move(r));
  });
}

void ExplorationRuntime::take_results() {
  worker_->rethrow_if_failed();
  std::vector<Result> results;
  {
    std::unique_lock<std::mutex> lock(results_mutex_, std::try_to_lock);
    if (!lock.owns_lock()) return;  // the task is handing a result over: take it next period
    results.swap(results_);
  }
  for (Result& r : results) {
    if (r.map) {
      map_in_flight_ = false;
      ++stats_.sets_integrated;
      correction_ = r.correction;
      heading_rate_ = r.heading_rate;
      if (!pose_override_) pose_ = compose(correction_, odom_pose_);
      if (r.shift) {
        explorer_.controller().shift(*r.shift);
        ++stats_.loop_closures;
      }
      stats_.scan_matches = r.scan_matches;
      stats_.scan_match_rejected = r.scan_match_rejected;
      stats_.relocalizations_held = r.relocalizations_held;
      stats_.relocalizations_new_space = r.relocalizations_new_space;
      stats_.relocalizations_ambiguous = r.relocalizations_ambiguous;
      stats_.relocalizations_in_obstacle = r.relocalizations_in_obstacle;
      stats_.relocalizations_at_edge = r.relocalizations_at_edge;
      stats_.relocalizations_asked = r.relocalizations_asked;
      stats_.scan_match_time_s = r.scan_match_time_s;
      note_relocalization(r.relocalizations, r.relocalization, r.relocalization_scores, r.relocalization_conflict, r.now_s);
      grid_copy_ = std::move(r.grid);
      frame_to_map_.add(r.frame_to_map_s);
      link_->map_seen();
      for (std::size_t i = 0; i < r.images.size() && i < sensors_.size(); ++i) sensors_[i]->recycle(std::move(r.images[i]));
    } else {
      decision_in_flight_ = false;
      if (r.nav && r.nav->goal) decision_latency_.add(r.done_wall_s - decision_asked_wall_);
    }
    plan_ = std::move(r.nav);
    nav_stats_ = r.nav_stats;
  }
}

void ExplorationRuntime::drain() {
  if (!worker_) return;
  worker_->wait_idle();
  take_results();
  if (visual_worker_) {
    visual_worker_->wait_idle();
    finish_visual(last_now_s_);
  }
}

void ExplorationRuntime::wait_background_idle() const {
  if (worker_) worker_->wait_idle();
  if (visual_worker_) visual_worker_->wait_idle();
}

}  // namespace duet
