// duet_ros: the duet exploration node (duet_node.hpp). `rosrun`-free: run the binary with ROS
// arguments (`duet_ros _profile:=dual _output_dir:=/tmp/maps odom:=/odom`) or from a launch file
// (ros/launch/duet.launch).
#include <duet_ros/duet_node.hpp>

#include <atomic>
#include <csignal>
#include <cstdio>
#include <exception>

namespace {
std::atomic<int> g_signal{0};
extern "C" void on_signal(int sig) { g_signal.store(sig); }
}  // namespace

int main(int argc, char** argv) {
  // Line-buffered: roslaunch (output="screen") or a log file gets each line as it is said, not
  // a block at exit.
  std::setvbuf(stdout, nullptr, _IOLBF, 0);
  // Our own SIGINT / SIGTERM handler: the node saves its maps before it shuts ROS down.
  ros::init(argc, argv, "duet", ros::init_options::NoSigintHandler);
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  try {
    ros::NodeHandle nh, pnh("~");
    duet_ros::DuetNode node(nh, pnh, duet_ros::read_options(pnh));
    const int rc = node.run(g_signal);
    ros::shutdown();
    return rc;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "duet_ros: %s\n", e.what());
    ros::shutdown();
    return 2;
  }
}
