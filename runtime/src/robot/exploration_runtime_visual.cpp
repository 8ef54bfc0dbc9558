// ExplorationRuntime's visual odometry (localization.visual_odometry): the synchronised sets it
// tracks and the health it reports (exploration_runtime.hpp, localization/visual_localization.hpp).
#include <duet/runtime/robot/background_worker.hpp>
#include <duet/runtime/robot/exploration_runtime.hpp>

#include <string>
#include <vector>

namespace duet {

void ExplorationRuntime::track_visual(const std::vector<RgbdImage>& images, const ApproximateTimeCore::Set& set, double now_s) {
  const std::size_t n = sensors_.size();
  double t = 0.0;
  for (std::size_t i = 0; i < n; ++i) t += set.stamps_s[i];
  t /= static_cast<double>(n);
  if (last_visual_t_ >= 0.0 && t < last_visual_t_ + 0.999 / settings_.visual_odometry.rate_hz && t >= last_visual_t_) return;
  last_visual_t_ = t;
  for (std::size_t i = 0; i < n; ++i)
    if (images[i].width == 0) {  // vision needs the same cameras every time: skip the set
      ++stats_.visual_sets_incomplete;
      return;
    }
  if (!worker_) {
    std::vector<SensorFrame> views;
    views.reserve(n);
    for (std::size_t i = 0; i < n; ++i) views.push_back(frame_view(images[i], profile_.sensors[i], profile_.sensors[i].T_robot_optical()));
    visual_->frames(views, t);
    stats_.visual = visual_->stats();
    update_health(now_s);
    return;
  }
  // kBackground: the front end (~10 ms a set) runs on its own worker on copies of the frames;
  // the EKF fuses its result when it is back (finish_visual), carried over the EKF's motion
  // since the frames' stamp. One set at a time: a set due while the last one runs is skipped.
  if (visual_in_flight_) {
    ++stats_.visual_sets_busy;
    return;
  }
  visual_images_.resize(n);
  visual_views_.clear();
  for (std::size_t i = 0; i < n; ++i) {
    visual_images_[i] = images[i];  // reuses the buffers of the previous set
    visual_views_.push_back(frame_view(visual_images_[i], profile_.sensors[i], profile_.sensors[i].T_robot_optical()));
  }
  visual_job_ = visual_->begin(t);
  visual_in_flight_ = true;
  visual_worker_->submit([this, job = visual_job_] {
    VisualLocalization::Tracked r = visual_->track(visual_views_, job);
    std::lock_guard<std::mutex> lock(visual_mutex_);
    visual_result_ = std::move(r);
  });
}

void ExplorationRuntime::finish_visual(double now_s) {
  if (!visual_worker_ || !visual_in_flight_) return;
  visual_worker_->rethrow_if_failed();
  std::optional<VisualLocalization::Tracked> r;
  {
    std::unique_lock<std::mutex> lock(visual_mutex_, std::try_to_lock);
    if (!lock.owns_lock()) return;  // the worker is handing its result over: take it next period
    r.swap(visual_result_);
  }
  if (!r) return;
  visual_in_flight_ = false;
  visual_->finish(visual_job_, *r);
  stats_.visual = visual_->stats();
  update_health(now_s);
}

void ExplorationRuntime::update_health(double now_s) {
  if (!visual_) return;
  const LocalizationHealth h = visual_->health(now_s);
  if (health_ && *health_ != h)
    guard_.note(now_s, std::string("localization health: ") + to_string(*health_) + " -> " + to_string(h) +
                           (h == LocalizationHealth::kGood ? "" : " (the wheels carry the pose)"));
  health_ = h;
}

std::optional<LocalizationHealth> ExplorationRuntime::localization_health() const noexcept { return health_; }

}  // namespace duet
