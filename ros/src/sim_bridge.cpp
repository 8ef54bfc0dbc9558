#include <duet_ros/map_messages.hpp>
#include <duet_ros/params.hpp>
#include <duet_ros/sim_bridge.hpp>

#include <duet/runtime/io/output.hpp>

#include <nav_msgs/Odometry.h>
#include <nlohmann/json.hpp>
#include <rosgraph_msgs/Clock.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>

#include <Eigen/Geometry>

#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <sstream>
#include <stdexcept>
#include <thread>
#include <unistd.h>

namespace duet_ros {
namespace {

double wall_now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

}  // namespace

BridgeOptions read_bridge_options(const ros::NodeHandle& pnh) {
  BridgeOptions o;
  o.world = param<std::string>(pnh, "world", o.world);
  o.profile = param<std::string>(pnh, "profile", o.profile);
  read_sets(pnh, o.sets);
  const int seed = param<int>(pnh, "seed", 1);
  require(seed >= 0, "~seed: negative");
  o.seed = static_cast<std::uint64_t>(seed);
  o.sensor_rate_hz = param<double>(pnh, "sensor_rate", o.sensor_rate_hz);
  require(o.sensor_rate_hz > 0.0 && o.sensor_rate_hz <= 60.0, "~sensor_rate: outside (0, 60] Hz");
  o.speed = param<double>(pnh, "speed", o.speed);
  o.threads = param<int>(pnh, "threads", o.threads);
  require(o.threads >= 0 && o.threads <= 256, "~threads: outside [0, 256]");
  require(o.speed >= 0.0 && o.speed <= 100.0, "~speed: outside [0, 100]");
  o.step_s = param<double>(pnh, "step", o.step_s);
  require(o.step_s >= 0.001 && o.step_s <= 0.1, "~step: outside [0.001, 0.1] s");
  o.max_time_s = param<double>(pnh, "max_time", o.max_time_s);
  require(o.max_time_s >= 0.0 && o.max_time_s <= 1e7, "~max_time: outside [0, 1e7] s");
  o.cmd_timeout_s = param<double>(pnh, "cmd_timeout", o.cmd_timeout_s);
  require(o.cmd_timeout_s > 0.0 && o.cmd_timeout_s <= 60.0, "~cmd_timeout: outside (0, 60] s");
  o.score_period_s = param<double>(pnh, "score_period", o.score_period_s);
  require(o.score_period_s >= 1.0 && o.score_period_s <= 3600.0, "~score_period: outside [1, 3600] s");
  o.summary = param<std::string>(pnh, "summary", o.summary);
  o.camera_stop_at_s = param<double>(pnh, "camera_stop_at", o.camera_stop_at_s);
  o.camera_stop_for_s = param<double>(pnh, "camera_stop_for", o.camera_stop_for_s);
  require(o.camera_stop_for_s >= 0.0, "~camera_stop_for: negative");
  o.malformed_at_s = param<double>(pnh, "malformed_at", o.malformed_at_s);
  o.odom_disorder_at_s = param<double>(pnh, "odom_disorder_at", o.odom_disorder_at_s);
  o.odom_frame = param<std::string>(pnh, "odom_frame", o.odom_frame);
  o.base_frame = param<std::string>(pnh, "base_frame", o.base_frame);
  return o;
}

SimBridge::SimBridge(ros::NodeHandle& nh, ros::NodeHandle& pnh, BridgeOptions options) : o_(std::move(options)), nh_(nh), pnh_(pnh) {
  if (!o_.summary.empty()) {  // checked now, not after the run (duet::Error names the folder)
    const std::filesystem::path parent = std::filesystem::path(o_.summary).parent_path();
    duet::prepare_output_dir(parent.empty() ? std::filesystem::path(".") : parent);
  }
  device_ = duet_device_new(("threads=" + std::to_string(o_.threads)).c_str());
  if (!device_) throw std::runtime_error("duet_sim_ros: no duet device");
  std::vector<std::string> sets = o_.sets;
  std::ostringstream rate;
  rate << "runtime.sensor_rate_hz=" << o_.sensor_rate_hz;
  sets.push_back(rate.str());
  std::vector<const char*> argv;
  for (const auto& s : sets) argv.push_back(s.c_str());
  sim_ = duet_sim_new(device_, o_.world.c_str(), DUET_PROFILE_NAME_OR_FILE, o_.profile.c_str(), argv.data(), argv.size(), o_.seed);
  if (!sim_) {
    const duet_error e = duet_device_get_error(device_);
    const std::string msg = duet_device_get_error_message(device_);
    duet_device_release(device_);
    throw std::runtime_error(std::string("duet_sim_ros: the world '") + o_.world + "' or the profile '" + o_.profile + "' (" +
                             duet_error_string(e) + "): " + msg);
  }
  const std::size_t n = duet_sim_get_sensor_count(sim_);
  std::vector<geometry_msgs::TransformStamped> mounts;
  for (std::size_t i = 0; i < n; ++i) {
    duet_runtime_sensor_info si{};
    duet_sim_get_sensor_info(sim_, i, &si);
    info_.push_back(si);
    names_.emplace_back(si.name);
    const std::string ns = names_.back();
    depth_pub_.push_back(nh_.advertise<sensor_msgs::Image>(ns + "/depth_registered/image_raw", 2));
    color_pub_.push_back(nh_.advertise<sensor_msgs::Image>(ns + "/rgb/image_rect_color", 2));
    info_pub_.push_back(nh_.advertise<sensor_msgs::CameraInfo>(ns + "/rgb/camera_info", 2));
    // The mount as a static transform base_link -> NAME_optical (for RViz and tf users).
    Eigen::Matrix4f T;
    std::memcpy(T.data(), si.T_robot_optical, sizeof si.T_robot_optical);
    const Eigen::Quaternionf q(T.topLeftCorner<3, 3>());
    geometry_msgs::TransformStamped t;
    t.header.frame_id = o_.base_frame;
    t.child_frame_id = ns + "_optical";
    t.transform.translation.x = T(0, 3);
    t.transform.translation.y = T(1, 3);
    t.transform.translation.z = T(2, 3);
    t.transform.rotation.x = q.x();
    t.transform.rotation.y = q.y();
    t.transform.rotation.z = q.z();
    t.transform.rotation.w = q.w();
    mounts.push_back(t);
  }
  static_tf_.sendTransform(mounts);
  clock_pub_ = nh_.advertise<rosgraph_msgs::Clock>("/clock", 10);
  odom_pub_ = nh_.advertise<nav_msgs::Odometry>("odom", 50);
  truth_pub_ = pnh_.advertise<nav_msgs::Odometry>("ground_truth", 50);
  cmd_sub_ = nh_.subscribe("cmd_vel", 10, &SimBridge::on_cmd, this, ros::TransportHints().tcpNoDelay());
  map_sub_ = nh_.subscribe("map", 1, &SimBridge::on_map, this);
}

SimBridge::~SimBridge() {
  if (sim_) duet_sim_release(sim_);
  if (device_) duet_device_release(device_);
}

void SimBridge::on_cmd(const geometry_msgs::TwistConstPtr& msg) {
  std::lock_guard lock(mutex_);
  ++cmds_received_;
  const float v = static_cast<float>(msg->linear.x), w = static_cast<float>(msg->angular.z);
  if (!std::isfinite(v) || !std::isfinite(w)) return;  // a motor driver ignores such a command
  cmd_ = duet_twist{v, w};
  cmd_t_ = now_.load();
}

void SimBridge::on_map(const nav_msgs::OccupancyGridConstPtr& msg) {
  std::lock_guard lock(mutex_);
  ++maps_received_;
  map_ = msg;
}

void SimBridge::publish_frames(double t) {
  if (o_.malformed_at_s >= 0.0 && t >= o_.malformed_at_s && malformed_published_ == 0 && !info_.empty()) {
    // Fault: a depth image of an encoding no depth camera uses, then one of the wrong size
    // (each with a colour image of the same stamp, so the pair reaches the node's checks).
    for (int k = 0; k < 2; ++k) {
      auto bad = boost::make_shared<sensor_msgs::Image>();
      bad->header.stamp = ros::Time(t + 0.001 * (k + 1));
      bad->header.frame_id = names_[0] + "_optical";
      bad->width = k == 0 ? static_cast<std::uint32_t>(info_[0].width) : 320;
      bad->height = k == 0 ? static_cast<std::uint32_t>(info_[0].height) : 240;
      bad->encoding = k == 0 ? "bgr16" : "16UC1";
      bad->step = (k == 0 ? 6 : 2) * bad->width;
      bad->data.assign(static_cast<std::size_t>(bad->step) * bad->height, 0);
      auto color = boost::make_shared<sensor_msgs::Image>();
      color->header = bad->header;
      color->width = bad->width;
      color->height = bad->height;
      color->encoding = "rgb8";
      color->step = 3 * bad->width;
      color->data.assign(static_cast<std::size_t>(color->step) * color->height, 128);
      color_pub_[0].publish(color);
      depth_pub_[0].publish(bad);
      ++malformed_published_;
    }
  }
  for (std::size_t i = 0; i < info_.size(); ++i) {
    const duet_runtime_sensor_info& si = info_[i];
    const std::size_t px = static_cast<std::size_t>(si.width) * static_cast<std::size_t>(si.height);
    depth_buf_.resize(px);
    rgb_buf_.resize(3 * px);
    double stamp = 0.0;
    while (duet_sim_take_frame(sim_, i, &stamp, depth_buf_.data(), 0, rgb_buf_.data(), 0, si.width, si.height) == 1) {
      if (i == 0 && o_.camera_stop_at_s >= 0.0 && stamp >= o_.camera_stop_at_s && stamp < o_.camera_stop_at_s + o_.camera_stop_for_s) {
        ++frames_withheld_;  // fault: the camera stopped
        continue;
      }
      std_msgs::Header h;
      h.stamp = ros::Time(stamp);
      h.frame_id = names_[i] + "_optical";
      auto depth = boost::make_shared<sensor_msgs::Image>();
      depth->header = h;
      depth->width = static_cast<std::uint32_t>(si.width);
      depth->height = static_cast<std::uint32_t>(si.height);
      depth->is_bigendian = 0;
      if (si.depth_units_per_m == 1000.0f) {  // REP 118: 16UC1 in millimetres
        depth->encoding = "16UC1";
        depth->step = 2 * depth->width;
        depth->data.resize(2 * px);
        std::memcpy(depth->data.data(), depth_buf_.data(), 2 * px);
      } else {  // other units: metres as 32FC1 (NaN: no return)
        depth->encoding = "32FC1";
        depth->step = 4 * depth->width;
        depth->data.resize(4 * px);
        for (std::size_t k = 0; k < px; ++k) {
          const float m = depth_buf_[k] ? depth_buf_[k] / si.depth_units_per_m : std::nanf("");
          std::memcpy(&depth->data[4 * k], &m, 4);
        }
      }
      auto color = boost::make_shared<sensor_msgs::Image>();
      color->header = h;
      color->width = depth->width;
      color->height = depth->height;
      color->encoding = "rgb8";
      color->step = 3 * color->width;
      color->data.assign(rgb_buf_.begin(), rgb_buf_.end());
      sensor_msgs::CameraInfo ci;
      ci.header = h;
      ci.width = depth->width;
      ci.height = depth->height;
      ci.distortion_model = "plumb_bob";
      ci.D.assign(5, 0.0);
      ci.K = {si.fx, 0.0, si.cx, 0.0, si.fy, si.cy, 0.0, 0.0, 1.0};
      ci.R = {1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0};
      ci.P = {si.fx, 0.0, si.cx, 0.0, 0.0, si.fy, si.cy, 0.0, 0.0, 0.0, 1.0, 0.0};
      info_pub_[i].publish(ci);
      color_pub_[i].publish(color);
      depth_pub_[i].publish(depth);
      ++frames_published_;
    }
  }
}

void SimBridge::publish_odometry() {
  double stamps[64];
  duet_pose2 poses[64];
  duet_twist twists[64];
  for (;;) {
    const std::size_t k = duet_sim_take_odometry(sim_, stamps, poses, twists, 64);
    for (std::size_t j = 0; j < k; ++j) {
      nav_msgs::Odometry m;
      m.header.stamp = ros::Time(stamps[j]);
      m.header.frame_id = o_.odom_frame;
      m.child_frame_id = o_.base_frame;
      m.pose.pose.position.x = poses[j].x;
      m.pose.pose.position.y = poses[j].y;
      m.pose.pose.orientation = yaw_quaternion(poses[j].theta);
      m.twist.twist.linear.x = twists[j].v;
      m.twist.twist.angular.z = twists[j].omega;
      odom_pub_.publish(m);
      if (o_.odom_disorder_at_s >= 0.0 && stamps[j] >= o_.odom_disorder_at_s && disordered_published_ == 0 && odometry_published_ > 30) {
        nav_msgs::Odometry old = last_odom_;  // fault: a message from 0.5 s ago arrives now
        odom_pub_.publish(old);
        ++disordered_published_;
      }
      if (odometry_published_ % 25 == 0) last_odom_ = m;
      geometry_msgs::TransformStamped t;
      t.header = m.header;
      t.child_frame_id = o_.base_frame;
      t.transform.translation.x = poses[j].x;
      t.transform.translation.y = poses[j].y;
      t.transform.rotation = m.pose.pose.orientation;
      tf_.sendTransform(t);
      ++odometry_published_;
    }
    if (k < 64) break;
  }
}

std::pair<double, double> SimBridge::score() {
  nav_msgs::OccupancyGridConstPtr map;
  {
    std::lock_guard lock(mutex_);
    map = map_;
  }
  if (!map) return {-1.0, 0.0};
  // Through map_server files: the same reader and the same scoring `duet explore` uses.
  const std::string stem = (std::filesystem::temp_directory_path() / ("duet_sim_ros_map." + std::to_string(::getpid()))).string();
  std::string error;
  if (!save_map_server(*map, stem, error)) {
    ROS_WARN_THROTTLE(30.0, "duet_sim_ros: cannot score the map: %s", error.c_str());
    return {-1.0, 0.0};
  }
  duet_grid grid = duet_grid_load_map_server(device_, (stem + ".yaml").c_str());
  double coverage = -1.0, area = 0.0;
  if (grid) {
    duet_sim_score(sim_, grid, &coverage, &area);
    duet_grid_release(grid);
  } else {
    ROS_WARN_THROTTLE(30.0, "duet_sim_ros: the map could not be read back: %s", duet_device_get_error_message(device_));
  }
  std::error_code ec;
  std::filesystem::remove(stem + ".pgm", ec);
  std::filesystem::remove(stem + ".yaml", ec);
  return {coverage, area};
}

int SimBridge::run(const std::atomic<int>& stop_flag) {
  ros::AsyncSpinner spinner(1);
  spinner.start();
  nlohmann::json curve = nlohmann::json::array();
  double t = 0.0, next_score = o_.score_period_s, path = 0.0;
  duet_pose2 last_true = duet_sim_get_true_pose(sim_);
  const double wall0 = wall_now();
  std::string why = "shut down";
  rosgraph_msgs::Clock clock;
  clock.clock = ros::Time(0.0);
  clock_pub_.publish(clock);
  publish_frames(0.0);  // the frames of t = 0
  while (ros::ok()) {
    if (stop_flag.load() != 0) {
      why = "interrupted by a signal";
      break;
    }
    if (o_.max_time_s > 0.0 && t >= o_.max_time_s - 1e-9) {
      why = "~max_time reached";
      break;
    }
    duet_twist cmd{0.0f, 0.0f};
    {
      std::lock_guard lock(mutex_);
      if (t - cmd_t_ <= o_.cmd_timeout_s) cmd = cmd_;
    }
    duet_sim_step(sim_, cmd, o_.step_s);
    t = duet_sim_get_time(sim_);
    now_.store(t);
    clock.clock = ros::Time(t);
    clock_pub_.publish(clock);
    publish_odometry();
    publish_frames(t);
    const duet_pose2 p = duet_sim_get_true_pose(sim_);
    path += std::hypot(p.x - last_true.x, p.y - last_true.y);
    last_true = p;
    nav_msgs::Odometry truth;
    truth.header.stamp = clock.clock;
    truth.header.frame_id = "world";
    truth.child_frame_id = o_.base_frame;
    truth.pose.pose.position.x = p.x;
    truth.pose.pose.position.y = p.y;
    truth.pose.pose.orientation = yaw_quaternion(p.theta);
    truth_pub_.publish(truth);
    if (t >= next_score) {
      const auto [coverage, area] = score();
      curve.push_back({{"t_s", t}, {"coverage", coverage}, {"explored_m2", area}, {"collisions", duet_sim_get_collisions(sim_)}});
      next_score += o_.score_period_s;
    }
    if (o_.speed > 0.0) {
      const double due = wall0 + t / o_.speed;
      const double now = wall_now();
      if (due > now) std::this_thread::sleep_for(std::chrono::duration<double>(due - now));
    }
  }
  ROS_INFO("duet_sim_ros: %s at t = %.2f s", why.c_str(), t);
  // The node publishes its last map when it stops: give it a moment to arrive.
  const double wait_until = wall_now() + 2.0;
  while (ros::ok() && wall_now() < wait_until && stop_flag.load() == 0) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  const auto [coverage, area] = score();
  spinner.stop();
  if (o_.summary.empty()) return 0;
  nlohmann::json s;
  {
    std::lock_guard lock(mutex_);
    s = {{"world", o_.world}, {"profile", o_.profile}, {"seed", o_.seed}, {"stop", why}, {"sim_time_s", t},
         {"wall_time_s", wall_now() - wall0}, {"coverage", coverage}, {"explored_area_m2", area},
         {"collisions", duet_sim_get_collisions(sim_)}, {"path_length_m", path}, {"frames_published", frames_published_},
         {"odometry_published", odometry_published_}, {"commands_received", cmds_received_}, {"maps_received", maps_received_},
         {"faults", {{"frames_withheld", frames_withheld_}, {"malformed_published", malformed_published_},
                     {"odometry_disordered", disordered_published_}}},
         {"sensor_rate_hz", o_.sensor_rate_hz}, {"speed", o_.speed}, {"threads", o_.threads}, {"curve", curve}};
  }
  try {
    duet::write_text_file(o_.summary, s.dump(2) + "\n");
  } catch (const std::exception& e) {
    ROS_ERROR("duet_sim_ros: %s", e.what());
    return 1;
  }
  ROS_INFO("duet_sim_ros: coverage %.1f %%, %zu collisions; wrote %s", 100.0 * coverage, static_cast<std::size_t>(duet_sim_get_collisions(sim_)),
           o_.summary.c_str());
  return 0;
}

}  // namespace duet_ros
