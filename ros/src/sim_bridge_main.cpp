// duet_sim_ros: duet's simulator as a ROS robot (sim_bridge.hpp). Run with use_sim_time
// (ros/launch/sim.launch sets it): `duet_sim_ros _world:=lab _seed:=1 _summary:=/tmp/sim.json`.
#include <duet_ros/sim_bridge.hpp>

#include <atomic>
#include <csignal>
#include <cstdio>
#include <exception>

namespace {
std::atomic<int> g_signal{0};
extern "C" void on_signal(int sig) { g_signal.store(sig); }
}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "duet_sim", ros::init_options::NoSigintHandler);
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  try {
    ros::NodeHandle nh, pnh("~");
    duet_ros::SimBridge bridge(nh, pnh, duet_ros::read_bridge_options(pnh));
    const int rc = bridge.run(g_signal);
    ros::shutdown();
    return rc;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "duet_sim_ros: %s\n", e.what());
    ros::shutdown();
    return 2;
  }
}
