// duet_ros_replay: maps a ROS 1 bag (bag_replay.hpp). `duet replay RUN.bag [options]` runs it
// with the same options; run it directly for the same result.
#include <duet_ros/bag_replay.hpp>

#include <atomic>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <string>

namespace {
std::atomic<int> g_signal{0};
extern "C" void on_signal(int sig) { g_signal.store(sig); }

int usage(const char* why) {
  std::fprintf(stderr,
               "duet_ros_replay: %s\n"
               "usage: duet_ros_replay BAG [-o DIR] [--profile P] [--set KEY=VALUE]... [--seed N] [--odom-topic T]\n"
               "                       [--imu-topic T] [--topic-prefix P] [--no-color] [-q]\n",
               why);
  return 2;
}
}  // namespace

int main(int argc, char** argv) {
  duet_ros::BagReplayOptions o;
  bool quiet = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&](const char* name) -> const char* {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "duet_ros_replay: %s needs a value\n", name);
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "-o" || a == "--out") o.output_dir = value("-o");
    else if (a == "--profile") o.profile = value("--profile");
    else if (a == "--set") o.sets.emplace_back(value("--set"));
    else if (a == "--seed") o.seed = std::strtoull(value("--seed"), nullptr, 10);
    else if (a == "--odom-topic") o.odom_topic = value("--odom-topic");
    else if (a == "--imu-topic") o.imu_topic = value("--imu-topic");
    else if (a == "--topic-prefix") o.topic_prefix = value("--topic-prefix");
    else if (a == "--no-color") o.sync.use_color = false;
    else if (a == "-q" || a == "--quiet") quiet = true;
    else if (!a.empty() && a[0] == '-') return usage(("unknown option " + a).c_str());
    else if (o.bag.empty()) o.bag = a;
    else return usage("more than one bag");
  }
  if (o.bag.empty()) return usage("no bag");
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  o.keep_going = [] { return g_signal.load() == 0; };
  try {
    const duet_ros::BagReplayResult r = duet_ros::replay_bag(o);
    if (!quiet && r.sensor_rate_hz != r.profile_sensor_rate_hz)
      std::fprintf(stderr, "duet replay: the bag's cameras run at %.1f Hz, the profile's at %.1f Hz: replayed with runtime.sensor_rate_hz=%.1f\n",
                   r.bag_sensor_rate_hz, r.profile_sensor_rate_hz, r.sensor_rate_hz);
    if (!quiet || r.interrupted)
      std::fprintf(stderr,
                   "duet replay: %s %s: %.1f s, %llu messages, %llu frames mapped, %llu dropped%s%s, %llu odometry; wrote %s/{grid.yaml, "
                   "grid.pgm, grid.png, cloud.pcd, trajectory.tum, summary.json}\n",
                   r.interrupted ? "interrupted" : "replayed", o.bag.c_str(), r.duration_s, static_cast<unsigned long long>(r.messages),
                   static_cast<unsigned long long>(r.frames_pushed), static_cast<unsigned long long>(r.frames_dropped),
                   r.last_drop.empty() ? "" : " (last: ", r.last_drop.empty() ? "" : (r.last_drop + ")").c_str(),
                   static_cast<unsigned long long>(r.odometry), o.output_dir.c_str());
    return r.interrupted ? 130 : 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "duet replay: %s\n", e.what());
    return 1;
  }
}
