#pragma once
/// @file blocked_escape.hpp
/// The way out for a robot the planner finds blocked: no cell within its planning radius is
/// traversable (a niche narrower than the inflation, or a pose estimate moved next to a wall),
/// so neither A* nor the dynamic window, both on the inflated grid, can move it.
///  - path_out(): the shortest 8-connected path of cell centres from the robot's cell to the
///    nearest traversable cell, through cells the body itself fits in (clearance at least the
///    chassis' radius; never tighter than where the robot already is);
///  - creep_along(): one control period along it - turn in place towards a point 0.15 m ahead,
///    then creep at 0.1 m/s, stopping short when the next position leaves that band.
/// The Navigator computes the path at each blocked decision (ExplorerSettings::blocked_recovery_s);
/// the Controller follows it while no goal is found (controller.hpp).
/// Frames: map frame. Thread safety: free functions, no shared state.
#include <duet/kernels/dwa.hpp>
#include <duet/kernels/inflation.hpp>

#include <Eigen/Core>

#include <optional>
#include <span>
#include <vector>

namespace duet {

/// Cell centres from the robot's cell (first) to the nearest traversable cell of `g` (last) by
/// path length, through cells with clearance_m >= min(body_radius_m, the robot cell's clearance)
/// (so a robot whose estimate sits on a wall can still leave it); at most max_length_m [m] long.
/// Empty when the robot is off the grid, already on a traversable cell, or none is in reach.
[[nodiscard]] std::vector<Eigen::Vector2f> path_out(const InflatedGrid& g, const Eigen::Vector2f& robot, float body_radius_m,
                                                    float max_length_m);

/// The twist of one control period along `path` (path_out()'s); nothing when the path is empty
/// or its end is reached (within one cell), or when moving on would take the body's centre to a
/// cell with less clearance than min(body_radius_m, the clearance here). Within the paper's
/// motion constraint (turn_in_place(); the linear speed ramps at the window's acceleration).
[[nodiscard]] std::optional<Twist> creep_along(const Pose2& robot, const Twist& current, std::span<const Eigen::Vector2f> path,
                                               const InflatedGrid& g, float body_radius_m, const DwaSettings& ds);

}  // namespace duet
