#pragma once
/// @file params.hpp
/// Private ROS parameters as the node and the simulator bridge read them: a missing parameter
/// keeps its default, a present one of the wrong type or out of range is an error naming it
/// (std::invalid_argument), and `~set` gives profile overrides.
#include <ros/node_handle.h>

#include <stdexcept>
#include <string>
#include <vector>

namespace duet_ros {

/// Throws std::invalid_argument(what) unless ok.
inline void require(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument(what);
}

/// ~name, or `fallback` when it is not set.
template <class T>
[[nodiscard]] T param(const ros::NodeHandle& pnh, const std::string& name, T fallback) {
  if (!pnh.hasParam(name)) return fallback;
  T v{};
  if (!pnh.getParam(name, v)) throw std::invalid_argument("~" + name + ": a value of the wrong type");
  return v;
}

/// Appends ~set's profile overrides to `out`: a list of "KEY=VALUE" strings or one string of
/// them separated by ';' (what a launch file's <param> can hold).
void read_sets(const ros::NodeHandle& pnh, std::vector<std::string>& out);

}  // namespace duet_ros
