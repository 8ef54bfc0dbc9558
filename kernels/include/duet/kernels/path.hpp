#pragma once
/// @file path.hpp
/// Global path search on the inflated grid (DESIGN.md §7: "the goal is reached through a global
/// path on the inflated grid, with the dynamic window following it"; the paper sends the goal of
/// §3.2 to its motion control without saying how; this is our global planner).
///
/// Graph: the traversable cells of an InflatedGrid (inflation.hpp), 8-connected. A diagonal step
/// is allowed only if both orthogonally adjacent cells it passes between are traversable (no
/// corner cutting past blocked cells). Step length: res (orthogonal) or sqrt(2)*res (diagonal).
///
/// Cost of a step from cell a to cell b (symmetric, so the cost of a path is the same both ways):
///     length * (1 + clearance_weight * (p(a) + p(b)) / 2),
///     p(c) = max(0, 1 - (clearance_m(c) - robot_radius_m) / clearance_decay_m)   (1 at the edge
///     of the inflation, falling linearly to 0 at clearance_decay_m beyond it).
/// The heuristic is the octile distance to the goal cell (or, with goal_tolerance_m > 0, the
/// Euclidean distance to the goal point minus the tolerance), admissible and consistent because
/// every step costs at least its length: A* returns a minimum-cost path.
///
/// Arithmetic: the search runs on fixed-point integer costs, unit u = resolution_m * 2^-F with
/// F = min(30, 62 - ceil(log2(bound on any f in cells))) (F = 30 for any grid up to 2^30 cells at
/// clearance_weight <= 1). An orthogonal step is exactly 2^F u, a diagonal one round(sqrt2 * 2^F) u,
/// plus the penalty part rounded to the nearest u; the integer octile heuristic uses the same step
/// lengths, so it stays exactly consistent. The returned path is optimal for these integer costs,
/// hence within 2^(1-F) cell lengths per step of the real optimum; result.cost is recomputed in double
/// along the returned path from the formula above.
/// Tie rule (deterministic, serial): the open cell with the smallest f is expanded first; among
/// equal f the one with the smallest heuristic (= largest g) first, the heuristic compared after a
/// right shift that makes it fit beside the cell index in 64 bits (no shift up to about 1400x1400
/// cells at F = 30, 1-2 bits at 2000x2000-4000x4000, i.e. to within 2^-28 cell lengths); then the
/// smallest cell index. Consequence on an open grid without clearance cost: all diagonal steps come
/// first, then the straight ones. Equal-cost paths are thus resolved identically on every run and
/// thread count.
///
/// Thread safety: plan_path() is serial and reentrant; concurrent calls need one PathWorkspace each.
#include <duet/kernels/inflation.hpp>

#include <Eigen/Core>

#include <cstdint>
#include <vector>

namespace duet {

struct PathSettings {
  bool allow_diagonal = true;       ///< 8-connected (true) or 4-connected (false)
  /// Extra cost per metre travelled next to the inflation border, >= 0 [1]. 1.0 doubles the cost
  /// of a step right at the border, so the planner accepts a detour of up to 2x to stay clear of
  /// walls but still takes the one narrow door that exists (paper Fig. 9: aisles 0.78-1.43 m, so a
  /// centred robot has only 0.19 m of clearance beyond its radius in the narrowest one).
  float clearance_weight = 1.0f;
  /// Distance beyond robot_radius_m over which the clearance penalty falls to 0, > 0 [m]. 0.3 m
  /// keeps the path in the middle of the paper's aisles (half-width minus radius 0.19-0.52 m) and
  /// about one braking distance (0.5 m/s, paper §4.2 exploration speed) off walls in open rooms.
  float clearance_decay_m = 0.30f;
  float goal_tolerance_m = 0.0f;    ///< accept any traversable cell whose centre is within this of the goal point, >= 0 [m]
};
/// Throws duet::Error(kInvalidArgument) naming the field: clearance_weight finite >= 0,
/// clearance_decay_m finite > 0, goal_tolerance_m finite >= 0.
void validate(const PathSettings& s);

enum class PathStatus {
  kFound,         ///< waypoints hold a path
  kStartBlocked,  ///< no traversable cell within robot_radius_m of the start cell
  kGoalBlocked,   ///< the goal cell (or every cell within goal_tolerance_m) is not traversable
  kNoPath,        ///< start and goal are in different traversable components
  kOutsideGrid,   ///< start or goal outside the grid (or not finite)
};
[[nodiscard]] const char* to_string(PathStatus s);

struct PathResult {
  PathStatus status = PathStatus::kNoPath;
  /// World coordinates of the cell centres from the start (or substitute start) cell to the goal
  /// cell, both included; empty unless kFound. One waypoint if start and goal share a cell.
  std::vector<Eigen::Vector2f> waypoints;
  float length_m = 0.0f;  ///< geometric length of the waypoint polyline [m] (0 unless kFound)
  float cost = 0.0f;      ///< weighted cost (see the file comment) [m]; >= length_m
  /// True if the start cell was not traversable and the search started from the nearest
  /// traversable cell within robot_radius_m (then waypoints[0] is that cell's centre).
  bool start_moved = false;
  std::size_t expanded = 0;  ///< cells expanded by the search (diagnostics)
};

/// Reusable buffers of plan_path (grow to the grid size, then reused without clearing: per-cell
/// records are tagged with a generation number, so a call touches only the cells it searches).
/// Not shareable between concurrent calls.
struct PathWorkspace {
  /// Heap entry (16 bytes): one 128-bit unsigned key hi:lo = [f][h >> shift | cell], so the heap
  /// compares one integer (see plan_path for the fixed-point units and the tie rule).
  struct Node {
    std::uint64_t lo;    ///< (heuristic >> shift) << cell_bits | cell
    std::uint64_t hi;    ///< f = g + h [fixed-point cost units]
  };
  struct CellRec {       ///< per-cell search record, valid when tag >> 1 == generation
    std::int64_t g;      ///< best cost so far [fixed-point cost units]
    std::uint32_t tag;   ///< 2 * generation (open) or 2 * generation + 1 (closed)
    std::uint32_t parent;
  };
  std::vector<CellRec> rec;
  std::vector<Node> heap;  ///< 4-ary min-heap
  std::vector<std::uint32_t> goal_stamp;  ///< goal-set membership (goal_tolerance_m > 0): == generation
  std::uint32_t generation = 0;
};

/// A* from start_xy to goal_xy on g (see the file comment). Checks, in order: kOutsideGrid (start
/// or goal point outside the grid), kStartBlocked, kGoalBlocked, then searches (kFound/kNoPath).
/// If the start cell is not traversable (the robot sits inside the inflation after a map update,
/// or its cell just turned unknown/occupied) the search starts from the nearest traversable cell
/// whose centre is within g.robot_radius_m of the start cell's centre (ties: smallest index) and
/// result.start_moved is set; the robot can reach it without crossing more than its own radius.
/// Throws duet::Error(kInvalidArgument) for invalid settings, an InflatedGrid whose buffers do not
/// match its size, or a clearance_weight too large for the fixed-point costs of this grid
/// (cell_count * (1 + clearance_weight) > ~2^57; e.g. clearance_weight > 2^35 on 2000x2000).
[[nodiscard]] PathResult plan_path(const InflatedGrid& g, const Eigen::Vector2f& start_xy, const Eigen::Vector2f& goal_xy,
                                   const PathSettings& s, PathWorkspace& ws);

/// The start-cell rule shared by plan_path and find_frontier: the cell index of `cell` if it is
/// traversable, else the nearest traversable cell with centre within g.robot_radius_m of its
/// centre (ties: smallest index), else -1. `cell` must be inside the grid.
[[nodiscard]] std::int64_t traversable_start(const InflatedGrid& g, const Eigen::Vector2i& cell);

}  // namespace duet
