// ExplorationRuntime's visual odometry (localization.visual_odometry): the synchronised sets it
// tracks and the health it reports (exploration_runtime.hpp, localization/visual_localization.hpp).
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
  std::vector<SensorFrame> views;
  views.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    if (images[i].width == 0) {  // vision needs the same cameras every time: skip the set
      ++stats_.visual_sets_incomplete;
      return;
    }
    views.push_back(frame_view(images[i], profile_.sensors[i], profile_.sensors[i].T_robot_optical()));
  }
  visual_->frames(views, t);
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
