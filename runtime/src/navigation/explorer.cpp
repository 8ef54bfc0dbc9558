/// @file explorer.cpp
/// Explorer: a Navigator and a Controller on one thread (see explorer.hpp).
#include <duet/runtime/navigation/explorer.hpp>

namespace duet {

namespace {
/// The controller's link to a navigator on the same thread: everything happens at once.
class InlineLink final : public GoalLink {
 public:
  explicit InlineLink(Navigator& n) : n_(n) {}
  NavPlanView plan() override { return n_.view(); }
  void trail(const Eigen::Vector2f& p) override { n_.add_trail(p); }
  void stall(const Eigen::Vector2f& contact, double now_s) override { n_.stall(contact, now_s); }
  void decide(const Pose2& robot, double now_s) override { n_.decide(robot, now_s); }
  void goal_reached(std::uint64_t id, double now_s) override { n_.goal_reached(id, now_s); }
  void abandon(std::uint64_t id, AbandonReason why, double now_s) override { n_.abandon(id, why, now_s); }

 private:
  Navigator& n_;
};
}  // namespace

ExplorerStats merge_stats(ExplorerStats s, const ControllerStats& c) {
  s.local_fallbacks = c.local_fallbacks;
  s.escapes = c.escapes;
  s.cornered_escapes = c.cornered_escapes;
  s.blocked_escapes = c.blocked_escapes;
  s.slowed = c.slowed;
  s.few_feature_periods = c.few_feature_periods;
  s.feature_seeks = c.feature_seeks;
  return s;
}

Explorer::Explorer(const Profile& profile, const ExplorerSettings& settings)
    : navigator_(profile, settings), controller_(profile, settings) {}

void Explorer::shift_frame(const Pose2& D) {
  navigator_.shift(D);
  controller_.shift(D);
}

Twist Explorer::control(const Pose2& robot, const Twist& current, double now_s) {
  InlineLink link(navigator_);
  return controller_.control(robot, current, now_s, link);
}

ExplorerStats Explorer::stats() const { return merge_stats(navigator_.stats(), controller_.stats()); }

}  // namespace duet
