#include <duet_ros/bag_replay.hpp>
#include <duet_ros/image_view.hpp>
#include <duet_ros/map_messages.hpp>

#include <duet.h>
#include <duet/runtime/io/output.hpp>

#include <nav_msgs/Odometry.h>
#include <nlohmann/json.hpp>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/Imu.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <memory>
#include <set>
#include <stdexcept>
#include <vector>

namespace duet_ros {
namespace {

struct Handles {
  duet_device device = nullptr;
  duet_runtime rt = nullptr;
  ~Handles() {
    if (rt) duet_runtime_release(rt);
    if (device) duet_device_release(device);
  }
};

[[noreturn]] void fail(const BagReplayOptions& o, const std::string& what) { throw std::runtime_error(o.bag + ": " + what); }

void check_api(const BagReplayOptions& o, duet_device d, const char* what) {
  if (const duet_error e = duet_device_get_error(d); e != DUET_ERROR_NONE)
    fail(o, std::string(what) + ": " + duet_error_string(e) + ": " + duet_device_get_error_message(d));
}

}  // namespace

BagReplayResult replay_bag(const BagReplayOptions& o) {
  BagReplayResult res;
  if (!ros::Time::isValid()) ros::Time::init();  // message_filters reads the clock; no master needed
  rosbag::Bag bag;
  try {
    bag.open(o.bag, rosbag::bagmode::Read);
  } catch (const rosbag::BagException& e) {
    fail(o, std::string("not a readable ROS 1 bag (") + e.what() + ")");
  }
  Handles h;
  h.device = duet_device_new("threads=0");
  if (!h.device) fail(o, "no duet device");
  std::vector<std::string> sets = o.sets;
  auto make_runtime = [&] {
    std::vector<const char*> argv;
    for (const auto& s : sets) argv.push_back(s.c_str());
    h.rt = duet_runtime_new(h.device, DUET_PROFILE_NAME_OR_FILE, o.profile.c_str(), argv.data(), argv.size(), o.seed);
    if (!h.rt) check_api(o, h.device, "the profile");
  };
  make_runtime();
  const std::size_t n = duet_runtime_get_sensor_count(h.rt);
  std::vector<duet_runtime_sensor_info> info(n);
  std::vector<std::string> depth_topic(n), color_topic(n), info_topic(n);
  std::vector<std::string> topics{o.odom_topic};
  if (!o.imu_topic.empty()) topics.push_back(o.imu_topic);
  for (std::size_t i = 0; i < n; ++i) {
    duet_runtime_get_sensor_info(h.rt, i, &info[i]);
    const std::string ns = o.topic_prefix + info[i].name;
    depth_topic[i] = ns + "/depth_registered/image_raw";
    color_topic[i] = ns + "/rgb/image_rect_color";
    info_topic[i] = ns + "/rgb/camera_info";
    topics.insert(topics.end(), {depth_topic[i], color_topic[i], info_topic[i]});
  }
  // The runtime expects frames at runtime.sensor_rate_hz (a silence is a sensor fault). Unless
  // the caller set it, it is the bag's own depth rate (frames per second of the busiest sensor).
  res.profile_sensor_rate_hz = n > 0 ? info[0].rate_hz : 0.0;
  res.sensor_rate_hz = res.profile_sensor_rate_hz;
  const bool rate_set = std::any_of(sets.begin(), sets.end(), [](const std::string& s) { return s.rfind("runtime.sensor_rate_hz=", 0) == 0; });
  try {
    // 1 / the median interval between a sensor's images: robust to a camera that stopped for a
    // while, to bursts when the recorder subscribed, and to extra (malformed) images.
    double best = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      rosbag::View v(bag, rosbag::TopicQuery(depth_topic[i]));
      std::vector<double> stamps;
      for (const rosbag::MessageInstance& m : v)  // the index only: nothing is read or decoded
        if (m.getDataType() == "sensor_msgs/Image") stamps.push_back(m.getTime().toSec());
      std::vector<double> dt;
      for (std::size_t k = 1; k < stamps.size(); ++k)
        if (stamps[k] > stamps[k - 1]) dt.push_back(stamps[k] - stamps[k - 1]);
      if (dt.size() < 9) continue;
      std::nth_element(dt.begin(), dt.begin() + static_cast<std::ptrdiff_t>(dt.size() / 2), dt.end());
      best = std::max(best, 1.0 / dt[dt.size() / 2]);
    }
    res.bag_sensor_rate_hz = best;
  } catch (const std::exception& e) {  // rosbag's and ros::Time's errors on a damaged bag
    fail(o, std::string("cannot be read (") + e.what() + ")");
  }
  if (!rate_set && res.bag_sensor_rate_hz > 0.0 && std::abs(res.bag_sensor_rate_hz - res.sensor_rate_hz) > 0.1 * res.sensor_rate_hz) {
    const double rate = std::round(res.bag_sensor_rate_hz * 10.0) / 10.0;
    sets.push_back("runtime.sensor_rate_hz=" + std::to_string(rate));
    duet_runtime_release(h.rt);
    h.rt = nullptr;
    make_runtime();
    res.sensor_rate_hz = rate;
  }
  std::unique_ptr<rosbag::View> view;
  try {
    view = std::make_unique<rosbag::View>(bag, rosbag::TopicQuery(topics));
  } catch (const rosbag::BagException& e) {
    fail(o, std::string("cannot be read (") + e.what() + ")");
  }
  if (view->size() == 0) {
    rosbag::View all(bag);
    std::set<std::string> have;
    for (const rosbag::ConnectionInfo* c : all.getConnections()) have.insert(c->topic);
    std::string list;
    for (const auto& t : have) list += (list.empty() ? "" : ", ") + t;
    std::string want;
    for (const auto& t : topics) want += (want.empty() ? "" : ", ") + t;
    fail(o, "no message on the node's topics (" + want + "); the bag has: " + (list.empty() ? "nothing" : list));
  }
  duet::prepare_output_dir(o.output_dir);

  std::vector<sensor_msgs::CameraInfoConstPtr> latest_info(n);
  std::vector<std::uint64_t> pushed(n, 0), dropped(n, 0);
  FrameSync sync(n, o.sync, [&](std::size_t i, const sensor_msgs::ImageConstPtr& d, const sensor_msgs::ImageConstPtr& c) {
    const RgbdView v = rgbd_view(*d, c.get(), latest_info[i].get(), info[i]);
    if (!v.error.empty()) {
      ++dropped[i];
      res.last_drop = std::string(info[i].name) + ": " + v.error;
      return;
    }
    const duet_rgbd_image img = v.c_image();
    duet_runtime_push_rgbd(h.rt, i, &img);
    ++pushed[i];
  });

  auto wrong_type = [&](const rosbag::MessageInstance& m, const char* want) {
    ++res.wrong_type;
    res.last_drop = m.getTopic() + ": a " + m.getDataType() + " message, not " + want;
  };
  const double period = duet_runtime_get_control_period(h.rt);
  double first = -1.0, next_spin = 0.0, last = 0.0;
  auto spin_until = [&](double t) {
    while (next_spin <= t) {
      duet_runtime_spin_once(h.rt, next_spin);
      ++res.control_periods;
      next_spin += period;
    }
  };
  try {
    for (const rosbag::MessageInstance& m : *view) {
      if (o.keep_going && !o.keep_going()) {
        res.interrupted = true;
        break;
      }
      const double t = m.getTime().toSec();
      if (first < 0.0) {
        first = t;
        next_spin = t + period;
      }
      spin_until(t);  // the control periods that passed before this message arrived
      last = t;
      ++res.messages;
      const std::string& topic = m.getTopic();
      if (topic == o.odom_topic) {
        auto od = m.instantiate<nav_msgs::Odometry>();
        if (!od) wrong_type(m, "nav_msgs/Odometry");
        if (od) {
          duet_runtime_push_odometry(h.rt, od->header.stamp.toSec(), planar_pose(*od), planar_twist(*od));
          ++res.odometry;
        }
        continue;
      }
      if (!o.imu_topic.empty() && topic == o.imu_topic) {
        auto imu = m.instantiate<sensor_msgs::Imu>();
        if (!imu) wrong_type(m, "sensor_msgs/Imu");
        if (imu) {
          duet_runtime_push_gyro(h.rt, imu->header.stamp.toSec(), static_cast<float>(imu->angular_velocity.z));
          ++res.imu;
        }
        continue;
      }
      for (std::size_t i = 0; i < n; ++i) {
        if (topic == depth_topic[i]) {
          if (auto img = m.instantiate<sensor_msgs::Image>()) sync.add_depth(i, img);
          else wrong_type(m, "sensor_msgs/Image");
        } else if (topic == color_topic[i]) {
          if (auto img = m.instantiate<sensor_msgs::Image>()) sync.add_color(i, img);
          else wrong_type(m, "sensor_msgs/Image");
        } else if (topic == info_topic[i]) {
          if (auto ci = m.instantiate<sensor_msgs::CameraInfo>()) latest_info[i] = ci;
          else wrong_type(m, "sensor_msgs/CameraInfo");
        }
      }
    }
  } catch (const ros::Exception& e) {  // rosbag's and the serializer's errors on a damaged bag
    fail(o, std::string("reading failed after ") + std::to_string(res.messages) + " messages (" + e.what() + ")");
  }
  spin_until(last + 1.0);  // the last frames' map update
  check_api(o, h.device, "replay");
  res.duration_s = first >= 0.0 ? last - first : 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    res.frames_pushed += pushed[i];
    res.frames_dropped += dropped[i];
  }
  duet_runtime_save(h.rt, o.output_dir.c_str());
  check_api(o, h.device, "saving the maps");
  const std::string path = o.output_dir + "/summary.json";
  std::ifstream in(path);
  nlohmann::json summary = nlohmann::json::parse(in);
  summary["bag"] = {{"file", o.bag},
                    {"duration_s", res.duration_s},
                    {"messages", res.messages},
                    {"frames_pushed", res.frames_pushed},
                    {"frames_dropped_malformed", res.frames_dropped},
                    {"wrong_type_dropped", res.wrong_type},
                    {"last_drop", res.last_drop},
                    {"sensor_rate_hz", res.sensor_rate_hz},
                    {"bag_sensor_rate_hz", res.bag_sensor_rate_hz},
                    {"profile_sensor_rate_hz", res.profile_sensor_rate_hz},
                    {"odometry", res.odometry},
                    {"imu", res.imu},
                    {"control_periods", res.control_periods},
                    {"interrupted", res.interrupted}};
  duet::write_text_file(path, summary.dump(2) + "\n");
  return res;
}

}  // namespace duet_ros
