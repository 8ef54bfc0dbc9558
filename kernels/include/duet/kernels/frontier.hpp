#pragma once
/// @file frontier.hpp
/// Global frontier search (paper §3.2): when the partial map simulation's reward R_g <= eps_R,
/// "frontiers between the known region and the unknown region are detected by means of a global
/// frontier search strategy based on a breadth-first search algorithm. The nearest connected
/// frontier point to the current mobile robot pose is selected, and the connected point is
/// defined as a point with eight existing grids around it."
///
/// Definitions (decided here where the paper is silent):
///  - Frontier cell: a cell with state kFree that has at least one kUnknown 8-neighbour inside the
///    grid (the area outside the grid is not "unknown").
///  - Connected frontier cell (§3.2): a frontier cell whose eight neighbours all lie inside the grid
///    (so it is not on the grid border). Only connected cells can be goals.
///  - Enclosed unknown pockets (min_unknown_region_m2 > 0): a frontier cell all of whose unknown
///    8-neighbours belong to an unknown region (8-connected kUnknown cells) smaller than
///    min_unknown_region_m2 that does not touch the grid border is not a frontier here: such a
///    region is the inside of an obstacle or the shadow of a pillar already seen from around it,
///    not a way on (in a cluttered building they outnumber the real frontiers and the robot would
///    chase them one by one). Regions are measured by a breadth-first search that stops as soon as
///    it proves the region large (enough cells, the grid border, or a cell already proved large).
///  - Cluster: an 8-connected component of frontier cells. Clusters of fewer than
///    min_cluster_cells cells are noise: find_frontier ignores their cells entirely (no goal, not
///    listed, do not count for the status). frontier_mask() reports raw frontier cells.
///  - Search: exact Dijkstra on path length in metres (orthogonal step = res, diagonal = sqrt(2) *
///    res, no corner cutting: the graph of plan_path with clearance_weight = 0) from the robot's
///    cell over the traversable cells of the InflatedGrid. Because there are only two step
///    lengths it runs as a "bucketed" Dijkstra with two FIFO queues (each receives cells in
///    non-decreasing distance), O(1) per cell instead of a heap. Distances are integers in units
///    of res / 65536 (orthogonal step 65536, diagonal round(sqrt(2) * 65536) = 92682, relative
///    error 2e-6 per diagonal step), so sums and the merge of the two queues are exact (no float
///    rounding decides the order); 64-bit costs take over for path lengths beyond ~65535 cells.
///    Reported lengths are converted to metres (the goal's from its exact step counts). A frontier cell is reached when it
///    is traversable and reached by the search. The robot's cell follows plan_path's start rule
///    (traversable_start in path.hpp: nearest traversable cell within robot_radius_m).
///  - Goal: the reached, connected, non-blacklisted frontier cell of a kept cluster with the
///    smallest path length >= min_goal_distance_m (compared with a tolerance of 1e-3 cell, so
///    that float sums like 10 x 0.05 m count as 0.5 m; ties: first popped, deterministic). `path` is
///    the shortest path to it (cell centres, robot cell first); it minimises length, not the
///    clearance-weighted cost of plan_path (re-plan with plan_path to follow it with clearance).
///  - Approach cells (approach_radius_m > 0): a frontier the robot cannot stand on anywhere (a
///    doorway seen from afar leaves a cone of known free cells narrower than the robot, and
///    observed-but-uncertain cells block by default) is still worth going to: the robot sees it
///    from nearby. A breadth-first search from the connected frontier cells of every kept cluster
///    without a traversable cell (in ascending index order) spreads over kFree cells (8-connected)
///    while within approach_radius_m (Euclidean, cell centres) of its source; a cell takes the
///    source of whichever wave reaches it first. The traversable, non-frontier cells it reaches
///    are approach cells: they count for their source's cluster exactly like frontier cells of
///    it (reachability, path length, goal candidacy, blacklist). The goal may then be an approach
///    cell; FrontierResult::target_xy is the frontier cell it looks at (= goal_xy otherwise).
///  - The search is not cut off at the goal: it covers the robot's whole traversable component so
///    that every cluster's reachability and distance are known.
///
/// Thread safety: GoalBlacklist is a value type (concurrent const use is safe; writes need
/// exclusive access). frontier_mask() and find_frontier() are reentrant; they run TBB-parallel
/// (frontier mask, frontier-cell list) in the caller's arena and their results do not depend on
/// the thread count; the pocket and approach searches, the clustering and the search are serial. One FrontierWorkspace per
/// concurrent call.
#include <duet/kernels/grid_view.hpp>
#include <duet/kernels/inflation.hpp>

#include <Eigen/Core>

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace duet {

/// Which reachable frontier becomes the goal.
enum class FrontierSelection {
  kNearest,     ///< the nearest by path length (Yamauchi 1997; the paper's fallback)
  /// explore_lite's frontier cost, per cluster: potential_scale * (Euclidean distance from the
  /// robot to its nearest cell [m]) - gain_scale * (its size [cells] * resolution [m]); the
  /// goal is the cheapest cluster's nearest eligible cell by path (explore_lite sends the
  /// cluster's centroid to move_base; here the goal must be a cell the planner can reach).
  kExploreLite,
};
[[nodiscard]] const char* to_string(FrontierSelection s);

struct FrontierSettings {
  int min_cluster_cells = 3;         ///< smaller frontier clusters are ignored (noise) [cells], >= 1
  float min_goal_distance_m = 0.5f;  ///< frontier goals nearer than this (path length) are skipped [m], >= 0 (paper §4.2: goals 0.5-10 m away)
  float blacklist_radius_m = 0.5f;   ///< a blacklisted goal blocks frontier cells within this (Euclidean, centre to goal) [m], >= 0
  /// Frontier cells the robot cannot stand on are reached through approach cells within this
  /// distance (see the file comment) [m], >= 0; 0 = only traversable frontier cells count (the
  /// paper's definition, the default here; the robot profiles choose their own).
  float approach_radius_m = 0.0f;
  /// Frontier cells that border only enclosed unknown regions smaller than this are ignored (see
  /// the file comment) [m^2], >= 0; 0 = every unknown region counts.
  float min_unknown_region_m2 = 0.0f;
  FrontierSelection selection = FrontierSelection::kNearest;
  float potential_scale = 3.0f;  ///< kExploreLite: weight of the distance [1/m], [0, 1e3] (explore_lite's default 3)
  float gain_scale = 1.0f;       ///< kExploreLite: weight of the size [1/m], [0, 1e3] (explore_lite's default 1)
};
/// Throws duet::Error(kInvalidArgument) naming the field and its range.
void validate(const FrontierSettings& s);

struct FrontierCluster {
  std::int32_t cells = 0;                   ///< frontier cells in the cluster
  Eigen::Vector2f centroid{0.0f, 0.0f};     ///< mean of the cell centres (world) [m]
  /// Reachable: the reached cell with the smallest path length. Otherwise: the cell whose centre is
  /// nearest (Euclidean) to the robot point (ties: smallest index). World [m].
  Eigen::Vector2f nearest_xy{0.0f, 0.0f};
  float path_length_m = 0.0f;  ///< path length from the robot to nearest_xy [m]; +inf if unreachable
  bool reachable = false;      ///< at least one of its cells was reached by the search
  /// Reachable, but every reached connected cell at >= min_goal_distance_m is blocked by the
  /// blacklist (and at least one such cell exists): the cluster offers no goal because of it.
  bool blacklisted = false;
};

enum class FrontierStatus {
  kFound,            ///< goal_xy and path are set
  kNoFrontier,       ///< no frontier cell (in a kept cluster) in the grid: exploration is complete
  kAllUnreachable,   ///< frontiers exist but the search reached no connected cell of them
  kAllBlacklisted,   ///< frontier cells were reached, but all are blacklisted or nearer than min_goal_distance_m
  kRobotBlocked,     ///< robot outside the grid, or no traversable cell within robot_radius_m of it
};
[[nodiscard]] const char* to_string(FrontierStatus s);

struct FrontierResult {
  FrontierStatus status = FrontierStatus::kNoFrontier;
  Eigen::Vector2f goal_xy{0.0f, 0.0f};    ///< centre of the goal cell (world) [m]; set iff kFound
  /// The frontier cell the goal is for (world) [m]: goal_xy for a frontier cell, the source
  /// frontier cell for an approach cell (see approach_radius_m); set iff kFound.
  Eigen::Vector2f target_xy{0.0f, 0.0f};
  float path_length_m = 0.0f;             ///< path length to the goal [m]; set iff kFound
  std::vector<Eigen::Vector2f> path;      ///< cell centres robot -> goal (world) [m]; empty unless kFound
  std::vector<FrontierCluster> clusters;  ///< kept clusters, ordered by their smallest cell index
  std::size_t frontier_cells = 0;         ///< frontier cells in kept clusters
  std::size_t reached_cells = 0;          ///< cells settled by the search (diagnostics)
};

/// Goals that failed or proved unreachable, each with an expiry time (the caller's clock, seconds;
/// kernels have no clock). An entry blocks while now_s < its expiry. Value type; not thread-safe
/// for concurrent writes.
class GoalBlacklist {
 public:
  struct Entry {
    Eigen::Vector2f xy;  ///< world [m]
    double expiry_s;     ///< caller's clock [s]
  };
  /// Adds xy until now_s + ttl_s. Throws duet::Error(kInvalidArgument) if xy or now_s is not finite
  /// or ttl_s is not > 0 (ttl_s = +inf: never expires).
  void add(Eigen::Vector2f xy, double now_s, double ttl_s);
  /// Removes the entries expired at now_s (expiry_s <= now_s).
  void expire(double now_s);
  /// True if a live entry (expiry_s > now_s) lies within radius_m of xy (Euclidean, inclusive).
  [[nodiscard]] bool blocks(Eigen::Vector2f xy, float radius_m, double now_s) const;
  /// Stored entries, including expired ones not yet removed by expire().
  [[nodiscard]] std::size_t size() const noexcept { return entries_.size(); }
  void clear() noexcept { entries_.clear(); }
  [[nodiscard]] const std::vector<Entry>& entries() const noexcept { return entries_; }

 private:
  std::vector<Entry> entries_;
};

/// Reusable buffers of find_frontier (grow to the grid size, reused without reallocation).
struct FrontierWorkspace {
  std::vector<std::uint8_t> mask;          ///< 1 = frontier cell (kept cluster after clustering), 3 = approach cell
  std::vector<std::uint32_t> approach_src; ///< approach BFS: source frontier cell of each visited cell (max = not visited)
  std::vector<std::uint32_t> approach_queue;  ///< approach BFS: the visited cells in visiting order
  std::vector<std::uint8_t> region;        ///< unknown-region verdicts: 0 not measured, 1 small, 2 large, 3 in the current search
  std::vector<std::uint32_t> region_cells; ///< cells with a verdict (reset after the call)
  std::vector<std::uint32_t> frontier;     ///< frontier cell indices, ascending
  std::vector<std::uint32_t> row_count;    ///< per-row frontier counts (parallel compaction)
  std::vector<std::int32_t> label;         ///< cluster id of frontier cells (valid where mask = 1)
  std::vector<std::uint32_t> stack;        ///< flood-fill stack
  std::vector<std::int32_t> cluster_raw;   ///< raw cluster id -> kept cluster id or -1
  std::vector<float> dist;                 ///< path length [m] of settled cells (+inf = not reached)
  std::vector<std::uint8_t> dir;           ///< unused (the path is traced back from the exact integer costs); kept for source compatibility
  struct QueueEntry {
    float d;             ///< tentative path length [m]
    std::uint32_t cell;
  };
  /// Unused since the search runs on integer costs (kept for source compatibility).
  std::vector<QueueEntry> q_orth, q_diag;
  std::vector<std::uint8_t> flags;         ///< search flags: traversable | frontier << 1 | border << 2
  std::vector<std::uint8_t> cand;          ///< per kept cluster: 0 none, 1 some candidate blocked, 2 goal-able
  std::vector<std::int64_t> cluster_goal;  ///< per kept cluster: its nearest goal-able cell by path (-1: none)
  /// Search cost of each cell in units of resolution_m / 65536 (orthogonal step 65536, diagonal
  /// 92682); max = not reached, 0 for blocked cells. cost64 is used only for paths beyond ~65535 cells.
  std::vector<std::uint32_t> cost32;
  std::vector<std::uint64_t> cost64;
  struct Entry32 {
    std::uint32_t d;  ///< cost (see cost32)
    std::uint32_t cell;
  };
  struct Entry64 {
    std::uint64_t d;
    std::uint32_t cell;
  };
  std::vector<Entry32> ring32_o, ring32_d;  ///< the two FIFO rings (orthogonal / diagonal step), power-of-2 size
  std::vector<Entry64> ring64_o, ring64_d;
};

/// Global frontier search (paper §3.2, see the file comment). Throws duet::Error(kInvalidArgument)
/// for invalid settings or an inconsistent InflatedGrid.
[[nodiscard]] FrontierResult find_frontier(const InflatedGrid& g, const Eigen::Vector2f& robot_xy, const GoalBlacklist& bl,
                                           double now_s, const FrontierSettings& s, FrontierWorkspace& ws);

/// Full parallel scan: mask[i] = 1 iff cell i is a frontier cell (kFree with a kUnknown
/// 8-neighbour inside the grid), else 0; returns the number of frontier cells. mask.size() must be
/// grid.cell_count(). TBB-parallel over fixed blocks of rows; independent of the thread count.
std::size_t frontier_mask(const GridView& grid, const CellThresholds& t, std::span<std::uint8_t> mask);

/// The same from already classified states (state.size() = width*height).
std::size_t frontier_mask(std::span<const CellState> state, int width, int height, std::span<std::uint8_t> mask);

/// True iff some frontier cell (as frontier_mask() defines it: kFree with a kUnknown 8-neighbour
/// inside the grid) has its centre within radius_m of xy (Euclidean, inclusive). Looks only at the
/// cells of the square around xy (O(radius^2), no mask). Used to end a frontier goal once its
/// frontier has been seen on the way. xy may lie outside the grid. Throws
/// duet::Error(kInvalidArgument) if xy or radius_m is not finite, radius_m < 0, or g.state does not
/// hold width * height cells. Reentrant.
[[nodiscard]] bool any_frontier_cell_within(const InflatedGrid& g, const Eigen::Vector2f& xy, float radius_m);

}  // namespace duet
