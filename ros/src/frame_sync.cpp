#include <duet_ros/frame_sync.hpp>

#include <message_filters/pass_through.h>
#include <message_filters/sync_policies/approximate_time.h>
#include <message_filters/synchronizer.h>

#include <boost/bind/bind.hpp>

#include <stdexcept>
#include <string>

namespace duet_ros {

using Image = sensor_msgs::Image;
using Policy = message_filters::sync_policies::ApproximateTime<Image, Image>;

struct FrameSync::Sensor {
  mutable std::mutex mutex;
  message_filters::PassThrough<Image> depth, color;
  std::unique_ptr<message_filters::Synchronizer<Policy>> sync;
  std::uint64_t pairs = 0;
};

FrameSync::FrameSync(std::size_t sensors, const FrameSyncSettings& settings, Handler handler)
    : settings_(settings), handler_(std::move(handler)) {
  if (sensors == 0) throw std::invalid_argument("FrameSync: no sensor");
  if (settings.queue < 1 || settings.queue > 1000)
    throw std::invalid_argument("FrameSync: queue " + std::to_string(settings.queue) + " is outside [1, 1000]");
  if (!(settings.max_interval_s > 0.0 && settings.max_interval_s <= 10.0))
    throw std::invalid_argument("FrameSync: max_interval_s " + std::to_string(settings.max_interval_s) + " is outside (0, 10]");
  if (!handler_) throw std::invalid_argument("FrameSync: no handler");
  for (std::size_t i = 0; i < sensors; ++i) {
    auto s = std::make_unique<Sensor>();
    if (settings_.use_color) {
      Policy policy(settings_.queue);
      policy.setMaxIntervalDuration(ros::Duration(settings_.max_interval_s));
      s->sync = std::make_unique<message_filters::Synchronizer<Policy>>(static_cast<const Policy&>(policy), s->depth, s->color);
      Sensor* raw = s.get();
      // boost::bind: the synchronizer calls with nine arguments, the bound call takes the first two.
      s->sync->registerCallback(boost::bind<void>(
          [this, raw, i](const sensor_msgs::ImageConstPtr& d, const sensor_msgs::ImageConstPtr& c) {
            ++raw->pairs;  // under raw->mutex: the add_*() that completed the pair holds it
            handler_(i, d, c);
          },
          boost::placeholders::_1, boost::placeholders::_2));
    }
    sensors_.push_back(std::move(s));
  }
}

FrameSync::~FrameSync() = default;

void FrameSync::add_depth(std::size_t sensor, const sensor_msgs::ImageConstPtr& msg) {
  Sensor& s = *sensors_.at(sensor);
  std::lock_guard lock(s.mutex);
  if (!settings_.use_color) {
    ++s.pairs;
    handler_(sensor, msg, nullptr);
    return;
  }
  s.depth.add(msg);
}

void FrameSync::add_color(std::size_t sensor, const sensor_msgs::ImageConstPtr& msg) {
  Sensor& s = *sensors_.at(sensor);
  if (!settings_.use_color) return;
  std::lock_guard lock(s.mutex);
  s.color.add(msg);
}

std::uint64_t FrameSync::pairs(std::size_t sensor) const {
  const Sensor& s = *sensors_.at(sensor);
  std::lock_guard lock(s.mutex);
  return s.pairs;
}

}  // namespace duet_ros
