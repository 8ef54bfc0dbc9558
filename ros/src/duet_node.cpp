#include <duet_ros/duet_node.hpp>
#include <duet_ros/params.hpp>
#include <duet_ros/image_view.hpp>
#include <duet_ros/map_messages.hpp>
#include <duet_ros/tf_mounts.hpp>

#include <duet/runtime/io/output.hpp>

#include <geometry_msgs/Twist.h>
#include <nlohmann/json.hpp>
#include <std_msgs/String.h>
#include <ros/topic.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include <chrono>
#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace duet_ros {
namespace {

double wall_now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

/// A ROS parameter value as the YAML scalar or flow list `--set` takes.
std::string yaml_value(const XmlRpc::XmlRpcValue& v, const std::string& key) {
  switch (v.getType()) {
    case XmlRpc::XmlRpcValue::TypeBoolean: return static_cast<bool>(const_cast<XmlRpc::XmlRpcValue&>(v)) ? "true" : "false";
    case XmlRpc::XmlRpcValue::TypeInt: return std::to_string(static_cast<int>(const_cast<XmlRpc::XmlRpcValue&>(v)));
    case XmlRpc::XmlRpcValue::TypeDouble: {
      std::ostringstream s;
      s.precision(17);
      s << static_cast<double>(const_cast<XmlRpc::XmlRpcValue&>(v));
      return s.str();
    }
    case XmlRpc::XmlRpcValue::TypeString: return static_cast<std::string>(const_cast<XmlRpc::XmlRpcValue&>(v));
    case XmlRpc::XmlRpcValue::TypeArray: {
      std::string out = "[";
      for (int i = 0; i < v.size(); ++i) out += (i ? ", " : "") + yaml_value(const_cast<XmlRpc::XmlRpcValue&>(v)[i], key);
      return out + "]";
    }
    default: throw std::invalid_argument("~config/" + key + ": a value of an unsupported type (a boolean, number, string or list is expected)");
  }
}

/// ~config's nested dictionary as KEY=VALUE lines (keys joined by '.').
void flatten(const XmlRpc::XmlRpcValue& v, const std::string& prefix, std::vector<std::string>& out) {
  if (v.getType() == XmlRpc::XmlRpcValue::TypeStruct) {
    for (auto it = const_cast<XmlRpc::XmlRpcValue&>(v).begin(); it != const_cast<XmlRpc::XmlRpcValue&>(v).end(); ++it)
      flatten(it->second, prefix.empty() ? it->first : prefix + "." + it->first, out);
    return;
  }
  out.push_back(prefix + "=" + yaml_value(v, prefix));
}

nlohmann::json latency_json(const duet::LatencyStats& l) {
  const duet::LatencySummary s = l.summary();
  return {{"count", s.count}, {"p50_ms", s.p50_s * 1e3}, {"p99_ms", s.p99_s * 1e3}, {"max_ms", s.max_s * 1e3}, {"mean_ms", s.mean_s * 1e3}};
}

}  // namespace

NodeOptions read_options(const ros::NodeHandle& pnh) {
  NodeOptions o;
  o.profile = param<std::string>(pnh, "profile", o.profile);
  read_sets(pnh, o.sets);
  if (pnh.hasParam("config")) {
    XmlRpc::XmlRpcValue v;
    pnh.getParam("config", v);
    require(v.getType() == XmlRpc::XmlRpcValue::TypeStruct, "~config: not a dictionary of profile keys");
    flatten(v, "", o.sets);
  }
  const int seed = param<int>(pnh, "seed", 1);
  require(seed >= 0, "~seed: " + std::to_string(seed) + " is negative");
  o.seed = static_cast<std::uint64_t>(seed);
  o.output_dir = param<std::string>(pnh, "output_dir", o.output_dir);
  o.map_frame = param<std::string>(pnh, "map_frame", o.map_frame);
  o.odom_frame = param<std::string>(pnh, "odom_frame", o.odom_frame);
  o.use_color = param<bool>(pnh, "use_color", o.use_color);
  o.use_imu = param<bool>(pnh, "use_imu", o.use_imu);
  o.sync.use_color = o.use_color;
  const int queue = param<int>(pnh, "sync_queue", static_cast<int>(o.sync.queue));
  require(queue >= 1 && queue <= 1000, "~sync_queue: " + std::to_string(queue) + " is outside [1, 1000]");
  o.sync.queue = static_cast<std::uint32_t>(queue);
  o.sync.max_interval_s = param<double>(pnh, "sync_max_interval", o.sync.max_interval_s);
  require(o.sync.max_interval_s > 0.0 && o.sync.max_interval_s <= 10.0, "~sync_max_interval: outside (0, 10] s");
  o.map_period_s = param<double>(pnh, "map_period", o.map_period_s);
  require(o.map_period_s >= 0.05 && o.map_period_s <= 3600.0, "~map_period: outside [0.05, 3600] s");
  o.cloud_period_s = param<double>(pnh, "cloud_period", o.cloud_period_s);
  require(o.cloud_period_s == 0.0 || (o.cloud_period_s >= 1.0 && o.cloud_period_s <= 3600.0), "~cloud_period: neither 0 nor in [1, 3600] s");
  o.transform_tolerance_s = param<double>(pnh, "transform_tolerance", o.transform_tolerance_s);
  require(o.transform_tolerance_s >= 0.0 && o.transform_tolerance_s <= 10.0, "~transform_tolerance: outside [0, 10] s");
  o.autostart = param<bool>(pnh, "autostart", o.autostart);
  o.save_on_exit = param<bool>(pnh, "save_on_exit", o.save_on_exit);
  o.exit_when_done = param<bool>(pnh, "exit_when_done", o.exit_when_done);
  o.max_time_s = param<double>(pnh, "max_time", o.max_time_s);
  o.threads = param<int>(pnh, "threads", o.threads);
  require(o.threads >= 0 && o.threads <= 256, "~threads: outside [0, 256]");
  o.mounts_from_tf = param<bool>(pnh, "mounts_from_tf", o.mounts_from_tf);
  o.base_frame = param<std::string>(pnh, "base_frame", o.base_frame);
  require(!o.base_frame.empty(), "~base_frame: empty");
  o.tf_wait_s = param<double>(pnh, "tf_wait", o.tf_wait_s);
  require(o.tf_wait_s > 0.0 && o.tf_wait_s <= 600.0, "~tf_wait: outside (0, 600] s");
  require(o.max_time_s >= 0.0 && o.max_time_s <= 1e7, "~max_time: outside [0, 1e7] s");
  return o;
}

/// One sensor's subscribers and counters.
struct DuetNode::SensorIo {
  ros::Subscriber depth, color, info;
  std::mutex mutex;  ///< guards the members below
  sensor_msgs::CameraInfoConstPtr latest_info;
  std::uint64_t depth_received = 0, color_received = 0, info_received = 0, pushed = 0, dropped = 0;
  std::string last_drop;
};

DuetNode::DuetNode(ros::NodeHandle& nh, ros::NodeHandle& pnh, NodeOptions options) : o_(std::move(options)), nh_(nh), pnh_(pnh) {
  duet::prepare_output_dir(o_.output_dir);  // a folder the maps cannot be saved in is an error now, not after the run
  device_ = duet_device_new(("threads=" + std::to_string(o_.threads)).c_str());
  if (device_ == nullptr) throw std::runtime_error(std::string("duet: no device: ") + duet_device_get_error_message(nullptr));
  duet_device_set_error_callback(device_, &DuetNode::on_error, this);
  std::vector<std::string> sets = o_.sets;
  sets.emplace_back("runtime.execution=background");  // control never waits for mapping or decisions
  make_runtime(sets);
  if (o_.mounts_from_tf) {
    // The sensors' mounts from tf (the drivers' and the robot description's frames), laid over the
    // profile's: the runtime is made again with them.
    try {
      for (const std::string& s : mounts_from_tf()) sets.push_back(s);
    } catch (...) {
      duet_runtime_release(rt_);
      duet_device_release(device_);
      rt_ = nullptr;
      device_ = nullptr;
      throw;
    }
    duet_runtime_release(rt_);
    rt_ = nullptr;
    make_runtime(sets);
  }
  period_s_ = duet_runtime_get_control_period(rt_);
  const std::size_t n = sensor_names_.size();
  if (!o_.autostart) duet_runtime_pause(rt_);

  sync_ = std::make_unique<FrameSync>(n, o_.sync, [this](std::size_t i, const sensor_msgs::ImageConstPtr& d, const sensor_msgs::ImageConstPtr& c) {
    on_pair(i, d, c);
  });
  const auto hints = ros::TransportHints().tcpNoDelay();
  for (std::size_t i = 0; i < n; ++i) {
    auto io = std::make_unique<SensorIo>();
    SensorIo* raw = io.get();
    const std::string ns = sensor_names_[i];
    io->depth = nh_.subscribe<sensor_msgs::Image>(ns + "/depth_registered/image_raw", 2, [this, i, raw](const sensor_msgs::ImageConstPtr& m) {
      { std::lock_guard lock(raw->mutex); ++raw->depth_received; }
      sync_->add_depth(i, m);
    }, ros::VoidConstPtr(), hints);
    if (o_.use_color)
      io->color = nh_.subscribe<sensor_msgs::Image>(ns + "/rgb/image_rect_color", 2, [this, i, raw](const sensor_msgs::ImageConstPtr& m) {
        { std::lock_guard lock(raw->mutex); ++raw->color_received; }
        sync_->add_color(i, m);
      }, ros::VoidConstPtr(), hints);
    io->info = nh_.subscribe<sensor_msgs::CameraInfo>(ns + "/rgb/camera_info", 2, [raw](const sensor_msgs::CameraInfoConstPtr& m) {
      std::lock_guard lock(raw->mutex);
      ++raw->info_received;
      raw->latest_info = m;
    });
    io_.push_back(std::move(io));
  }
  odom_sub_ = nh_.subscribe("odom", 50, &DuetNode::on_odometry, this, hints);
  if (o_.use_imu) imu_sub_ = nh_.subscribe("imu", 200, &DuetNode::on_imu, this, hints);

  cmd_pub_ = nh_.advertise<geometry_msgs::Twist>("cmd_vel", 1);
  map_pub_ = nh_.advertise<nav_msgs::OccupancyGrid>("map", 1, true);
  cloud_pub_ = pnh_.advertise<sensor_msgs::PointCloud2>("cloud", 1, true);
  goal_pub_ = pnh_.advertise<geometry_msgs::PoseStamped>("goal", 1, true);
  path_pub_ = pnh_.advertise<nav_msgs::Path>("path", 1, true);
  frontier_pub_ = pnh_.advertise<visualization_msgs::MarkerArray>("frontiers", 1, true);
  state_pub_ = pnh_.advertise<std_msgs::String>("state", 1, true);
  event_pub_ = pnh_.advertise<std_msgs::String>("events", 20);

  auto trigger = [this](const char* name, auto fn) {
    return pnh_.advertiseService<std_srvs::Trigger::Request, std_srvs::Trigger::Response>(
        name, [fn](std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res) {
          fn(res);
          return true;
        });
  };
  start_srv_ = trigger("start", [this](std_srvs::Trigger::Response& res) {
    duet_runtime_resume(rt_);
    res.success = true;
    res.message = "exploring";
  });
  stop_srv_ = trigger("stop", [this](std_srvs::Trigger::Response& res) {
    duet_runtime_stop(rt_);
    res.success = true;
    res.message = "stopped by the operator";
  });
  home_srv_ = trigger("return_home", [this](std_srvs::Trigger::Response& res) {
    duet_runtime_return_home(rt_);
    res.success = true;
    res.message = "returning home";
  });
  save_srv_ = trigger("save", [this](std_srvs::Trigger::Response& res) { res.success = save(o_.output_dir, res.message); });
}

void DuetNode::make_runtime(const std::vector<std::string>& sets) {
  std::vector<const char*> argv;
  for (const auto& s : sets) argv.push_back(s.c_str());
  rt_ = duet_runtime_new(device_, DUET_PROFILE_NAME_OR_FILE, o_.profile.c_str(), argv.data(), argv.size(), o_.seed);
  if (rt_ == nullptr) {
    const duet_error e = duet_device_get_error(device_);
    const std::string msg = duet_device_get_error_message(device_);
    duet_device_release(device_);
    device_ = nullptr;
    throw std::runtime_error(std::string("duet: the profile '") + o_.profile + "' (" + duet_error_string(e) + "): " + msg);
  }
  std::string overrides;
  for (const auto& s : sets) overrides += (overrides.empty() ? "" : "; ") + s;
  ROS_INFO("duet: profile %s, seed %llu, %zu override(s)%s%s", o_.profile.c_str(), static_cast<unsigned long long>(o_.seed), sets.size(),
           sets.empty() ? "" : ": ", overrides.c_str());
  duet_runtime_set_event_callback(rt_, &DuetNode::on_event, this);
  sensor_info_.clear();
  sensor_names_.clear();
  const std::size_t n = duet_runtime_get_sensor_count(rt_);
  for (std::size_t i = 0; i < n; ++i) {
    duet_runtime_sensor_info info{};
    duet_runtime_get_sensor_info(rt_, i, &info);
    sensor_info_.push_back(info);
    sensor_names_.emplace_back(info.name);  // the topics' namespace
  }
}

std::vector<std::string> DuetNode::mounts_from_tf() {
  tf2_ros::Buffer buffer;
  tf2_ros::TransformListener listener(buffer);
  std::vector<std::string> sets;
  for (std::size_t i = 0; i < sensor_names_.size(); ++i) {
    const std::string topic = sensor_names_[i] + "/depth_registered/image_raw";
    const std::string who = "~mounts_from_tf: sensor " + std::to_string(i) + " (" + sensor_names_[i] + ")";
    ROS_INFO("duet: waiting up to %.0f s for %s to learn its frame", o_.tf_wait_s, nh_.resolveName(topic).c_str());
    const auto image = ros::topic::waitForMessage<sensor_msgs::Image>(topic, nh_, ros::Duration(o_.tf_wait_s));
    if (!image) throw std::runtime_error(who + ": no image on " + nh_.resolveName(topic) + " within ~tf_wait = " + std::to_string(o_.tf_wait_s) + " s");
    if (image->header.frame_id.empty()) throw std::runtime_error(who + ": its images on " + nh_.resolveName(topic) + " name no frame (header.frame_id is empty)");
    geometry_msgs::TransformStamped T;
    try {
      T = buffer.lookupTransform(o_.base_frame, image->header.frame_id, ros::Time(0), ros::Duration(o_.tf_wait_s));
    } catch (const tf2::TransformException& e) {
      throw std::runtime_error(who + ": no transform " + o_.base_frame + " <- " + image->header.frame_id + " in tf: " + e.what());
    }
    try {
      for (std::string& s : mount_overrides(i, sensor_names_[i], T.transform)) {
        ROS_INFO("duet: %s (from tf %s <- %s)", s.c_str(), o_.base_frame.c_str(), image->header.frame_id.c_str());
        sets.push_back(std::move(s));
      }
    } catch (const std::invalid_argument& e) {
      throw std::runtime_error(std::string("~mounts_from_tf: ") + e.what());
    }
  }
  return sets;
}

DuetNode::~DuetNode() {
  running_ = false;
  odom_cv_.notify_all();
  if (control_thread_.joinable()) control_thread_.join();
  if (publish_thread_.joinable()) publish_thread_.join();
  if (rt_ != nullptr) duet_runtime_release(rt_);
  if (device_ != nullptr) duet_device_release(device_);
}

void DuetNode::on_error(void* self, duet_error code, const char* message) {
  auto* node = static_cast<DuetNode*>(self);
  {
    std::lock_guard lock(node->mutex_);
    ++node->push_errors_;
  }
  ROS_ERROR_THROTTLE(5.0, "duet: %s: %s", duet_error_string(code), message);
}

void DuetNode::on_event(void* self, double time_s, const char* message) {
  auto* node = static_cast<DuetNode*>(self);
  ROS_INFO("duet: t=%.2f %s", time_s, message);
  std_msgs::String m;
  m.data = message;
  node->event_pub_.publish(m);
}

void DuetNode::on_pair(std::size_t sensor, const sensor_msgs::ImageConstPtr& depth, const sensor_msgs::ImageConstPtr& color) {
  SensorIo& io = *io_[sensor];
  sensor_msgs::CameraInfoConstPtr info;
  {
    std::lock_guard lock(io.mutex);
    info = io.latest_info;
  }
  const RgbdView view = rgbd_view(*depth, color.get(), info.get(), sensor_info_[sensor]);
  if (!view.error.empty()) {
    {
      std::lock_guard lock(io.mutex);
      ++io.dropped;
      io.last_drop = view.error;
    }
    ROS_WARN_THROTTLE(5.0, "duet: %s: frame at %.3f dropped: %s", sensor_names_[sensor].c_str(), view.image.stamp_s, view.error.c_str());
    return;
  }
  const duet_rgbd_image img = view.c_image();
  duet_runtime_push_rgbd(rt_, sensor, &img);
  std::lock_guard lock(io.mutex);
  ++io.pushed;
}

void DuetNode::on_odometry(const nav_msgs::OdometryConstPtr& msg) {
  const double arrived = wall_now();
  const duet_pose2 pose = planar_pose(*msg);
  duet_runtime_push_odometry(rt_, msg->header.stamp.toSec(), pose, planar_twist(*msg));  // bad values: counted drops in the runtime
  {
    std::lock_guard lock(mutex_);
    ++odometry_received_;
    if (std::isfinite(pose.x) && std::isfinite(pose.y) && std::isfinite(pose.theta)) {
      odom_pose_ = pose;
      odom_seen_ = true;
    }
    odom_wall_s_ = arrived;
  }
  odom_cv_.notify_one();
}

void DuetNode::on_imu(const sensor_msgs::ImuConstPtr& msg) {
  duet_runtime_push_gyro(rt_, msg->header.stamp.toSec(), static_cast<float>(msg->angular_velocity.z));
  std::lock_guard lock(mutex_);
  ++imu_received_;
}

void DuetNode::control_loop() {
  // A period is due every period_s of ROS time. It starts with the first odometry message that
  // arrives within a quarter period of its due time (the command answers the newest odometry at
  // once: a Kobuki's 50 Hz odometry gives periods of 40 and 60 ms, 50 on average); with no
  // odometry it starts on its own a quarter period late, so the runtime sees the silence and
  // holds the robot still.
  double next_due = -1.0, last_t = -1e300;
  while (running_) {
    double odom_wall = -1.0;
    {
      std::unique_lock lock(mutex_);
      odom_cv_.wait_for(lock, std::chrono::duration<double>(period_s_ * 0.1), [&] { return !running_ || odom_wall_s_ >= 0.0; });
      odom_wall = odom_wall_s_;
      odom_wall_s_ = -1.0;
    }
    if (!running_) break;
    const double now = ros::Time::now().toSec();
    if (next_due < 0.0) next_due = now;
    const bool by_odom = odom_wall >= 0.0 && now >= next_due - 0.25 * period_s_;
    const bool by_timeout = now >= next_due + 0.25 * period_s_;
    if (!by_odom && !by_timeout) continue;
    const double t = std::max(now, last_t);
    tick(t, by_odom, odom_wall);
    last_t = t;
    next_due += period_s_;
    if (next_due < now - period_s_) next_due = now + period_s_;  // fell behind (a paused clock, a slow machine): start afresh
  }
}

void DuetNode::tick(double now_s, bool by_odometry, double odom_wall_s) {
  const double start = wall_now();
  duet_runtime_spin_once(rt_, now_s);
  const duet_twist cmd = duet_runtime_get_command(rt_);
  geometry_msgs::Twist t;
  t.linear.x = cmd.v;
  t.angular.z = cmd.omega;
  cmd_pub_.publish(t);
  const double published = wall_now();
  duet_runtime_status st{};
  duet_runtime_get_status(rt_, &st);
  duet_pose2 odom{};
  bool seen = false;
  {
    std::lock_guard lock(mutex_);
    odom = odom_pose_;
    seen = odom_seen_;
    ++ticks_;
    if (!by_odometry) ++ticks_by_timeout_;
    if (by_odometry) topic_to_command_.add(published - odom_wall_s);
    if (last_tick_start_ >= 0.0) control_period_.add(start - last_tick_start_);
  }
  last_tick_start_ = start;
  // One map -> odom per stamp: tf2 warns of (and drops) a second one with the same time.
  if (seen && std::isfinite(st.pose.x) && now_s > last_tf_s_) {
    tf_.sendTransform(map_to_odom(st.pose, odom, o_.map_frame, o_.odom_frame, ros::Time(now_s + o_.transform_tolerance_s)));
    last_tf_s_ = now_s;
  }
  if (st.state == DUET_EXPLORER_DONE) done_ = true;
}

void DuetNode::publish_maps(bool with_cloud) {
  const ros::Time stamp = ros::Time::now();
  duet_grid grid = duet_runtime_get_grid(rt_);
  if (grid != nullptr) {
    const nav_msgs::OccupancyGrid map = to_occupancy_grid(grid, o_.map_frame, stamp);
    duet_grid_release(grid);
    if (map.info.width > 0) {
      map_pub_.publish(map);
      frontier_pub_.publish(frontier_markers(map));
    }
  }
  duet_runtime_status st{};
  duet_runtime_get_status(rt_, &st);
  if (st.has_goal) goal_pub_.publish(to_pose_stamped(st.goal, o_.map_frame, stamp));
  const std::size_t n = duet_runtime_get_path(rt_, nullptr, 0, 0);
  std::vector<float> xy(2 * n);
  const std::size_t got = n ? duet_runtime_get_path(rt_, xy.data(), 0, n) : 0;
  xy.resize(2 * std::min(n, got));
  path_pub_.publish(to_path(xy, o_.map_frame, stamp));
  std::string state = duet_explorer_state_string(st.state);
  if (st.paused) state = "paused";
  if (st.state == DUET_EXPLORER_DONE) {
    const std::size_t len = duet_runtime_get_stop_detail(rt_, nullptr, 0);
    std::string detail(len + 1, '\0');
    duet_runtime_get_stop_detail(rt_, detail.data(), detail.size());
    detail.resize(len);
    state += ": " + detail;
  }
  bool changed = false;
  {
    std::lock_guard lock(mutex_);
    changed = state != last_state_;
    last_state_ = state;
  }
  if (changed) {
    std_msgs::String m;
    m.data = state;
    state_pub_.publish(m);
    ROS_INFO("duet: %s", state.c_str());
  }
  if (with_cloud) {
    duet_cloud cloud = duet_runtime_get_cloud(rt_);  // waits for the map update in flight
    if (cloud != nullptr) {
      cloud_pub_.publish(to_point_cloud2(cloud, o_.map_frame, stamp));
      duet_cloud_release(cloud);
    }
  }
}

void DuetNode::publish_loop() {
  double next_map = wall_now(), next_cloud = o_.cloud_period_s > 0.0 ? wall_now() + o_.cloud_period_s : 1e300;
  while (running_) {
    const double now = wall_now();
    if (now >= next_map) {
      const bool cloud = now >= next_cloud;
      publish_maps(cloud);
      next_map = now + o_.map_period_s;
      if (cloud) next_cloud = now + o_.cloud_period_s;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

bool DuetNode::save(const std::string& dir, std::string& message) {
  std::lock_guard save_lock(save_mutex_);
  duet_device_get_error(device_);  // clear
  duet_runtime_save(rt_, dir.c_str());
  if (const duet_error e = duet_device_get_error(device_); e != DUET_ERROR_NONE) {
    message = std::string("save to ") + dir + " failed: " + duet_device_get_error_message(device_);
    ROS_ERROR("duet: %s", message.c_str());
    return false;
  }
  // The node's own figures beside the runtime's, in summary.json.
  nlohmann::json ros_block;
  {
    std::lock_guard lock(mutex_);
    ros_block["topic_to_command"] = latency_json(topic_to_command_);
    ros_block["control_period"] = latency_json(control_period_);
    ros_block["ticks"] = ticks_;
    ros_block["ticks_without_odometry"] = ticks_by_timeout_;
    ros_block["odometry_received"] = odometry_received_;
    ros_block["imu_received"] = imu_received_;
    ros_block["c_api_errors"] = push_errors_;
  }
  nlohmann::json sensors = nlohmann::json::array();
  for (std::size_t i = 0; i < io_.size(); ++i) {
    SensorIo& io = *io_[i];
    // Not under io.mutex: FrameSync holds its own lock while it calls on_pair, which takes io.mutex
    // (the other order deadlocked a save against an arriving frame).
    const std::uint64_t pairs = sync_->pairs(i);
    std::lock_guard lock(io.mutex);
    sensors.push_back({{"name", sensor_names_[i]}, {"depth_received", io.depth_received}, {"color_received", io.color_received},
                       {"camera_info_received", io.info_received}, {"pairs", pairs}, {"pushed", io.pushed},
                       {"dropped_malformed", io.dropped}, {"last_drop", io.last_drop}});
  }
  ros_block["sensors"] = sensors;
  const std::string path = dir + "/summary.json";
  try {
    std::ifstream in(path);
    nlohmann::json summary = nlohmann::json::parse(in);
    summary["ros"] = ros_block;
    duet::write_text_file(path, summary.dump(2) + "\n");
  } catch (const std::exception& e) {
    message = "saved to " + dir + ", but summary.json could not be extended: " + e.what();
    ROS_ERROR("duet: %s", message.c_str());
    return false;
  }
  message = "saved to " + dir;
  ROS_INFO("duet: %s", message.c_str());
  return true;
}

int DuetNode::run(const std::atomic<int>& stop_flag) {
  // With use_sim_time the clock is 0 until /clock arrives: wait for it.
  while (ros::ok() && stop_flag.load() == 0 && ros::Time::now().isZero()) ros::WallDuration(0.01).sleep();
  const double t0 = ros::Time::now().toSec();
  ros::AsyncSpinner spinner(2);
  spinner.start();
  control_thread_ = std::thread([this] { control_loop(); });
  publish_thread_ = std::thread([this] { publish_loop(); });
  std::string why = "shut down";
  while (ros::ok()) {
    if (stop_flag.load() != 0) {
      why = "interrupted by a signal";
      break;
    }
    if (o_.max_time_s > 0.0 && ros::Time::now().toSec() - t0 >= o_.max_time_s) {
      why = "~max_time reached";
      break;
    }
    if (o_.exit_when_done && done_.load()) {
      why = "the explorer is done";
      break;
    }
    ros::WallDuration(0.05).sleep();
  }
  running_ = false;
  odom_cv_.notify_all();
  if (control_thread_.joinable()) control_thread_.join();
  if (publish_thread_.joinable()) publish_thread_.join();
  cmd_pub_.publish(geometry_msgs::Twist());  // the robot stops
  ROS_INFO("duet: %s; stopping", why.c_str());
  int rc = 0;
  if (o_.save_on_exit) {
    publish_maps(true);
    std::string message;
    rc = save(o_.output_dir, message) ? 0 : 1;
  }
  spinner.stop();
  return rc;
}

}  // namespace duet_ros
