#pragma once
/// @file unexplored.hpp
/// What exploration left, where and why (issue 23): when the explorer stops, the frontier cells
/// of its last search are grouped into regions (8-connected), and each region gets a reason -
///  - kReachable:  the robot could still go there (the run stopped for another reason);
///  - kAbandoned:  it could go there, but its goals failed (time limit, stuck, no path) N times;
///  - kLookedAt:   it could go there, stood at it or looked at it from a view goal, and it
///                 stayed a frontier (the inside of an obstacle seen through a gap in its outline);
///  - kNarrowGap:  the widest known-free passage to it (widest_passage(), bottleneck.hpp) is
///                 narrower than the robot: gap_m against needed_m;
///  - kNoKnownWay: no known-free cell path joins it to the robot (seen across unknown space or
///                 over an obstacle).
/// The stop detail lists the largest regions (describe()); summary.json lists them all.
/// Computed once, when the explorer stops (O(N log N) on the planning grid), never per period.
#include <duet/kernels/frontier.hpp>
#include <duet/kernels/inflation.hpp>

#include <Eigen/Core>

#include <cstddef>
#include <span>
#include <string>
#include <vector>

namespace duet {

enum class LeftWhy { kReachable, kAbandoned, kLookedAt, kNarrowGap, kNoKnownWay };
[[nodiscard]] const char* to_string(LeftWhy w);

/// Goals abandoned near one place (map frame), counted by the navigator.
struct GoalFailures {
  Eigen::Vector2f xy{0.0f, 0.0f};  ///< where the first of them was meant to go [m]
  int count = 0;
};

struct UnexploredRegion {
  Eigen::Vector2f centroid{0.0f, 0.0f};  ///< mean of its frontier cells (map frame) [m]
  Eigen::Vector2f nearest{0.0f, 0.0f};   ///< its frontier cell nearest the robot (Euclidean) [m]
  int cells = 0;                         ///< frontier cells
  float length_m = 0.0f;                 ///< cells * resolution [m]
  LeftWhy why = LeftWhy::kReachable;
  /// Width of the widest known-free passage from the robot to it, at its narrowest point: 2 x the
  /// bottleneck clearance - one cell (exact for an odd number of free cells across, one cell
  /// short for an even one) [m]; 0 when no passage exists, +inf when the grid has no obstacle.
  float gap_m = 0.0f;
  /// What the robot needs: 2 x the planning radius [m] (it passes where the clearance at the
  /// narrowest point exceeds the radius).
  float needed_m = 0.0f;
  int failures = 0;                      ///< goals abandoned within the blacklist radius of its cells
  bool looked_at = false;                ///< a looked-at point lies within the blacklist radius of its cells
};

struct UnexploredSettings {
  float blacklist_radius_m = 0.5f;  ///< failures and looked-at points within this of a cell count [m], >= 0
  int min_cells = 1;                ///< smaller regions are not listed, >= 1
  /// The frontier search's FrontierSettings::approach_radius_m [m], >= 0: a region is reached at
  /// its own cells, or at free cells within this distance of them (through free cells).
  float approach_radius_m = 0.0f;
};

/// The regions of `frontier` (cell centres in g's frame, e.g. Navigator::frontier_points()) on
/// `g`, largest first. A point outside g is ignored. `looked_at`: frontier cells the robot stood
/// at or looked at from a view goal (the blacklist's permanent entries, ViewGoal's). Empty when
/// `frontier` is.
[[nodiscard]] std::vector<UnexploredRegion> find_unexplored(const InflatedGrid& g, const Eigen::Vector2f& robot_xy,
                                                            std::span<const Eigen::Vector2f> frontier,
                                                            std::span<const GoalFailures> failures,
                                                            std::span<const Eigen::Vector2f> looked_at,
                                                            const UnexploredSettings& s = {});

/// "3 regions left: 40 cells (2.0 m) at (12.3, 4.5) behind a 0.35 m gap (the robot needs
/// 0.40 m); ..." - at most `max_listed` regions, then how many more. Empty for no region.
[[nodiscard]] std::string describe(std::span<const UnexploredRegion> regions, std::size_t max_listed = 4);

}  // namespace duet
