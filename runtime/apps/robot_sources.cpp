// The robot sources `duet run --robot NAME[:ARGUMENT]` knows (robot_source.hpp). A new source is
// its own file (a RobotSource and a RobotSourceKind) plus one line here.
#include "commands.hpp"

#include <duet/sim/sim_robot.hpp>

namespace duet::app {

const RobotSourceRegistry& robot_sources() {
  static const RobotSourceRegistry registry = [] {
    RobotSourceRegistry r;
    r.add(sim::sim_robot_source());  // sim:WORLD - the simulator
    return r;
  }();
  return registry;
}

}  // namespace duet::app
