#pragma once
/// @file frame_sync.hpp
/// Pairs each sensor's depth and colour images by message_filters' ApproximateTime policy (the
/// ROS drivers publish them separately, stamped a few ms apart), and hands each pair on. The
/// same object serves the node (fed by subscribers) and bag replay (fed from the bag in its
/// recorded order), so both pair a stream the same way.
///
/// Without colour (`use_color` false) every depth image is handed on alone.
/// Pairs further apart than `max_interval_s` are never made (a colour stream that stops leaves
/// the depth stream unpaired: the runtime then sees a silent sensor and says so).
/// Thread safety: add_*() from any thread (one lock per sensor); the handler runs on the thread
/// of the add_*() call that completed the pair.
#include <sensor_msgs/Image.h>

#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <vector>

namespace duet_ros {

struct FrameSyncSettings {
  bool use_color = true;        ///< pair colour with depth (else depth alone)
  std::uint32_t queue = 10;     ///< ApproximateTime's queue per topic, [1, 1000]
  double max_interval_s = 0.05; ///< a pair's stamps at most this far apart [s], (0, 10]
};

class FrameSync {
 public:
  /// A pair: `color` is null without colour.
  using Handler = std::function<void(std::size_t sensor, const sensor_msgs::ImageConstPtr& depth, const sensor_msgs::ImageConstPtr& color)>;
  /// Throws std::invalid_argument for 0 sensors, settings out of range or an empty handler.
  FrameSync(std::size_t sensors, const FrameSyncSettings& settings, Handler handler);
  ~FrameSync();
  FrameSync(const FrameSync&) = delete;
  FrameSync& operator=(const FrameSync&) = delete;

  /// A sensor index out of range throws std::out_of_range.
  void add_depth(std::size_t sensor, const sensor_msgs::ImageConstPtr& msg);
  void add_color(std::size_t sensor, const sensor_msgs::ImageConstPtr& msg);
  /// Pairs handed on for a sensor.
  [[nodiscard]] std::uint64_t pairs(std::size_t sensor) const;

 private:
  struct Sensor;
  FrameSyncSettings settings_;
  Handler handler_;
  std::vector<std::unique_ptr<Sensor>> sensors_;
};

}  // namespace duet_ros
