/*
 * duet_planner.h - the exploration planner in the C API of duet (its settings, status codes,
 * results and calls) and scan-to-map matching on a grid.
 * Part of duet.h: include duet.h, not this file directly. The conventions at the top of
 * duet.h (handles, errors, buffers, settings, thread safety, frames) hold here.
 */
#include "duet.h" /* before the guard: alone, this file then declares all of duet.h in order */
#ifndef DUET_PLANNER_H
#define DUET_PLANNER_H

#ifdef __cplusplus
extern "C" {
#endif

/* ============================================================================================
 * Exploration planner (paper §3, Fig. 6)
 *
 * A duet_planner holds everything the exploration and control kernels need between calls:
 *   - a copy of a 2D log-odds grid (the map frame of "Occupancy grid" in duet_grid.h: row-major, row 0
 *     at the lowest y, NaN = unknown), the observation model built on it (ray fans of the
 *     sensors, entropy Eq. (5), DDA or Embree backend) and its inflated grid (exact Euclidean
 *     clearance to the nearest blocked cell, traversable cells for a round robot);
 *   - the sensors' horizontal sectors (default: the paper's two Kinects, Eq. (6), 30 rays each,
 *     as duet_paper_dual_sensors(out, 30));
 *   - a goal blacklist (goals that failed, with an expiry time on the caller's clock);
 *   - the dynamic window's state between control steps (oscillation detection, recovery);
 *   - reusable workspaces, so repeated calls do not allocate once warmed up.
 * The planner owns its copy of the grid: duet_planner_set_grid*() copy the cells, and later
 * changes of the caller's buffer or duet_grid are seen only at the next set_grid call.
 *
 * Rules common to every duet_planner_* function below:
 *   - A planner is created by a device, holds a reference to it, and reports its errors there.
 *   - Thread safety: all calls on one planner are serialized by the planner's mutex (a second
 *     thread waits); calls on distinct planners run in parallel inside the shared device arena.
 *     Results never depend on the device's thread count.
 *   - Every function that needs the map (all but new/retain/release, set_grid*, set_sensors,
 *     get_sensors, get_ray_count, get_grid_size, the blacklist functions and dwa_reset) fails
 *     with DUET_ERROR_INVALID_OPERATION ("no grid") until a set_grid call succeeded.
 *   - Poses, points and times must be finite (else DUET_ERROR_INVALID_ARGUMENT naming the
 *     argument). A required output pointer that is NULL is DUET_ERROR_INVALID_ARGUMENT.
 *   - Variable-size outputs (paths, trajectories, clusters) go to caller arrays with a capacity
 *     in elements: min(capacity, full count) elements are written, and the result struct holds
 *     the FULL count, so a caller whose capacity was too small can call again with a bigger
 *     array (the results are deterministic). capacity 0 with a NULL array is valid (counts
 *     only); a NULL array with a non-zero capacity is DUET_ERROR_INVALID_ARGUMENT.
 *   - On error the outputs are left unchanged and the planner's state (grid, blacklist, dynamic
 *     window state) is unchanged, except where stated.
 *   - Settings pointers may be NULL (defaults); see "Settings" at the top of duet.h.
 * ========================================================================================== */

typedef struct duet_planner_t* duet_planner;

/* Planar pose in the map frame: x, y [m], heading theta [rad] counter-clockwise from +x. */
typedef struct duet_pose2 {
  float x, y, theta;
} duet_pose2;

/* --------------------------------------------------------------------------------------------
 * Scan-to-map matching (kernels/scan_match.hpp): the planar pose near a prior at which 2D
 * obstacle points (robot frame, e.g. an RGB-D frame's points between two heights) best lie on
 * the grid's occupied cells - a likelihood field exp(-d^2 / (2 sigma^2)) of the distance d to the
 * nearest occupied cell centre, searched over a lattice around the prior and refined, each
 * candidate weighted by a Gaussian prior on its offset. The runtime corrects the wheel odometry
 * with it at every map update.
 * -------------------------------------------------------------------------------------------- */

typedef struct duet_scan_match_settings {
  float linear_window_m;    /* search +-this in x and y around the prior [m], [0, 5] (default 0.15) */
  float angular_window_deg; /* search +-this in heading [deg], [0, 45] (default 1.5) */
  float linear_step_m;      /* lattice step in x and y [m], (0, 1] (default 0.05) */
  float angular_step_deg;   /* lattice step in heading [deg], (0, 10] (default 0.5) */
  float sigma_m;            /* std of the likelihood field [m], (0, 1] (default 0.05) */
  float max_distance_m;     /* distances clamped to this [m], (0, 10] (default 0.25) */
  float prior_sigma_m;      /* std of the translation prior [m], > 0 (default 0.1) */
  float prior_sigma_deg;    /* std of the heading prior [deg], > 0 (default 2) */
  size_t min_points;        /* fewer finite points: DUET_SCAN_MATCH_TOO_FEW_POINTS, >= 1 (default 50) */
  float min_score;          /* best mean score below this: NOT_CONFIDENT, [0, 1] (default 0.35) */
} duet_scan_match_settings;

DUET_API void duet_scan_match_settings_init(duet_scan_match_settings* settings);

enum duet_scan_match_status {
  DUET_SCAN_MATCH_MATCHED = 0,         /* pose is the best candidate */
  DUET_SCAN_MATCH_TOO_FEW_POINTS = 1,  /* pose is the prior */
  DUET_SCAN_MATCH_NOT_CONFIDENT = 2,   /* pose is the prior (best score below min_score) */
};

typedef struct duet_scan_match_result {
  int status;             /* enum duet_scan_match_status */
  duet_pose2 pose;        /* the matched pose, or the prior */
  float score;            /* mean likelihood of `pose` over the points, [0, 1] */
  float prior_score;      /* ... of the prior */
  size_t candidates;      /* poses scored */
} duet_scan_match_result;

/* Matches `count` 2D points (x, y [m] in the robot frame; 2 floats at xy_stride bytes, 0 =
 * packed; non-finite points are skipped but count in the mean) against `grid` around `prior`
 * (map frame) and writes the result to *out. The distance field is computed from the grid on
 * every call (one Euclidean distance transform of the whole grid, a few ms for 1000 x 1000
 * cells): occupied = log-odds >= 0.619 (p >= 0.65). Errors (DUET_ERROR_INVALID_ARGUMENT): NULL
 * out, a NULL or misaligned buffer with count > 0, a non-finite prior, invalid settings (the
 * message names the field); *out is then unchanged. Parallel inside (the device's threads);
 * the result does not depend on the thread count. Thread-safe (shared on `grid`). */
DUET_API void duet_grid_scan_match(duet_grid grid, const float* xy, size_t xy_stride, size_t count,
                                   duet_pose2 prior, const duet_scan_match_settings* settings,
                                   duet_scan_match_result* out);

/* Differential-drive command: forward speed v [m/s], yaw rate omega [rad/s] (ccw positive). */
typedef struct duet_twist {
  float v, omega;
} duet_twist;

/* One sensor's horizontal fan in the robot frame (paper §3.1: a sector of radius max range,
 * centre angle = horizontal field of view; extrinsics as Eq. (6)). Ray r of a fan of n > 1 rays
 * points at yaw + theta - fov/2 + fov * r / (n - 1); a single ray points along the axis. */
typedef struct duet_sensor_sector {
  float x_m, y_m;      /* sensor origin in the robot frame [m] (default 0, 0) */
  float yaw_rad;       /* optical axis yaw in the robot frame [rad] (default 0) */
  float fov_rad;       /* horizontal field of view, (0, 2 pi] [rad] (default 57 deg) */
  float min_range_m;   /* cells nearer are not observed, >= 0 [m] (default 0.5) */
  float max_range_m;   /* finite, >= min_range_m [m] (default 5.0) */
  int rays;            /* rays in the fan, [1, 100000] (default 30) */
} duet_sensor_sector;

/* Fills one sector with the defaults above (a Kinect at the robot's origin facing forward).
 * NULL is ignored. Thread-safe. */
DUET_API void duet_sensor_sector_init(duet_sensor_sector* sector);

/* The paper's robot (Eq. (6)): out[0] at (-0.118, 0) yaw 0 (forward), out[1] at (-0.118, 0)
 * yaw -90 deg (facing right); 57 deg, 0.5-5 m, `rays_per_sensor` rays each ([1, 100000]).
 * Needs no device: errors (NULL out, bad ray count) go to the no-device slot and leave `out`
 * unchanged. Thread-safe. */
DUET_API void duet_paper_dual_sensors(duet_sensor_sector out[2], int rays_per_sensor);

/* Log-odds thresholds of the three cell states used by all planning kernels: a cell is
 * occupied if l >= occupied_logodds, free if l <= free_logodds, else (and NaN) unknown.
 * Finite, free_logodds < occupied_logodds. Defaults log(0.65/0.35) and log(0.45/0.55): one
 * hit (0.85) is occupied and one miss (-0.4) free, as duet_grid_copy_ros(..., 0.65, 0.45). */
typedef struct duet_cell_thresholds {
  float occupied_logodds; /* (default 0.6190392) */
  float free_logodds;     /* (default -0.2006707) */
} duet_cell_thresholds;

enum duet_observation_backend {
  DUET_OBSERVATION_EMBREE = 0, /* Embree BVH over the occupied cells' faces, then an entropy walk */
  DUET_OBSERVATION_DDA = 1     /* one 2D DDA walk: entropy sum and first occupied cell together */
};

/* Observation model (paper §3.1): a ray stops at the first occupied cell; the entropy of the
 * cells it crossed (hit cell included, cells outside the grid = unknown = 1 bit) is what it
 * observes. Both backends give the same results (but for rays grazing a cell corner within
 * ~1e-5 m); DDA is the default because it is faster on every benchmark. */
typedef struct duet_observation_settings {
  duet_cell_thresholds thresholds;          /* what stops a ray */
  enum duet_observation_backend backend;    /* (default DUET_OBSERVATION_DDA) */
  int tile_cells;                           /* Embree scene tile edge [cells], [1, 65536] (default 64) */
} duet_observation_settings;

DUET_API void duet_observation_settings_init(duet_observation_settings* settings);

/* Inflation: a cell is blocked if occupied; or observed but neither free nor occupied (its
 * hits and misses disagree, as on a wall face seen at a grazing angle) when
 * uncertain_is_obstacle = 1 (the default); or never observed when unknown_is_obstacle = 1;
 * clearance = exact Euclidean distance from a cell's centre to the nearest blocked cell's
 * centre [m] (+inf if there is none; the area outside the grid is not blocked); a cell is
 * traversable iff it is free and its clearance > robot_radius_m. */
typedef struct duet_inflation_settings {
  duet_cell_thresholds thresholds;
  float robot_radius_m;    /* finite, >= 0 [m] (default 0.20: Kobuki 0.177 m + margin) */
  int unknown_is_obstacle; /* 0 or 1 (default 0) */
  int uncertain_is_obstacle; /* 0 or 1 (default 1) */
} duet_inflation_settings;

DUET_API void duet_inflation_settings_init(duet_inflation_settings* settings);

/* Global path (A*, 8-connected, no corner cutting) on the traversable cells. Step cost
 * length * (1 + clearance_weight * (p(a) + p(b)) / 2), p(c) = max(0, 1 - (clearance(c) -
 * robot_radius) / clearance_decay_m): paths keep away from walls but take narrow doors. */
typedef struct duet_path_settings {
  int allow_diagonal;       /* 1 = 8-connected, 0 = 4-connected (default 1) */
  float clearance_weight;   /* finite, >= 0 (default 1.0) */
  float clearance_decay_m;  /* finite, > 0 [m] (default 0.30) */
  float goal_tolerance_m;   /* any traversable cell within this of the goal ends the path, >= 0 [m] (default 0) */
} duet_path_settings;

DUET_API void duet_path_settings_init(duet_path_settings* settings);

/* Global frontier search (paper §3.2): frontier cell = free cell with an unknown 8-neighbour
 * inside the grid; cluster = 8-connected frontier cells; goal = the nearest (path length over
 * traversable cells) connected (not on the grid border), non-blacklisted frontier cell of a
 * cluster of >= min_cluster_cells cells, at least min_goal_distance_m away. */
typedef struct duet_frontier_settings {
  int min_cluster_cells;      /* smaller clusters are ignored [cells], >= 1 (default 3) */
  float min_goal_distance_m;  /* nearer goals are skipped [m], >= 0 (default 0.5) */
  float blacklist_radius_m;   /* a blacklisted goal blocks cells within this [m], >= 0 (default 0.5) */
  /* Frontier cells the robot cannot stand on are reached through traversable "approach" cells
   * within this distance, found by a breadth-first search over known-free cells from them [m],
   * >= 0 (default 0 = only traversable frontier cells count). */
  float approach_radius_m;
  /* Frontier cells that border only enclosed unknown regions (8-connected unknown cells not
   * touching the grid border) smaller than this are ignored: the inside of an obstacle, the
   * shadow of a pillar [m^2], >= 0 (default 0 = every region counts). */
  float min_unknown_region_m2;
} duet_frontier_settings;

DUET_API void duet_frontier_settings_init(duet_frontier_settings* settings);

/* Partial map simulation: the paper's Procedure 1 (§3.2), a particle method over motion
 * series. N particles, I iterations, H stages of stage_dt_s each; phi_i = phi_a * i + phi_b
 * observation samples in iteration i ([1, 1000] for every i). The result is a pure function
 * of the inputs and `seed` (any thread count). Ranges are checked as the C++ kernel does. */
typedef struct duet_partial_sim_settings {
  int iterations;                /* I, [1, 1000] (default 5) */
  int particles;                 /* N, [1, 100000] (default 100) */
  int phi_a, phi_b;              /* (default 1, 1) */
  int stages;                    /* H, [1, 100] (default 4) */
  float stage_dt_s;              /* duration of each simulated motion, (0, 60] [s] (default 1.0) */
  float v_min_mps, v_max_mps;    /* U_range of v, in [-10, 10], v_min <= v_max, v_max > 0 [m/s] (default 0.1, 0.5) */
  float omega_max_rps;           /* U_range of |omega|, [0, 100] [rad/s] (default 0.8) */
  float sigma_v_mps;             /* Sigma of zeta_i, i >= 2, [0, 10] [m/s] (default 0.08) */
  float sigma_omega_rps;         /* [0, 100] [rad/s] (default 0.3) */
  float resample_ess_fraction;   /* eps_N = fraction * N, (0, 1] (default 0.5) */
  float gamma;                   /* discount of line 19, (0, 10] (default 0.9) */
  float unknown_hit_probability; /* chi: P(unknown cell occupied), (0, 1) (default 0.02) */
  float hit_logodds;             /* inverse sensor model, hit (default 0.85) */
  float miss_logodds;            /* inverse sensor model, miss (default -0.4) */
  float ism_noise_logodds;       /* half-width of the l_ISM noise, [0, |miss_logodds|) (default 0.1) */
  float min_logodds, max_logodds; /* posterior clamp (default -2.0, 3.5) */
  float min_goal_distance_m;     /* goals nearer to the robot are rejected [m] (default 0.5) */
  float max_goal_distance_m;     /* goals farther are rejected [m] (default 10.0) */
  float collision_step_m;        /* rollouts checked every this [m] (default 0.025) */
  uint64_t seed;                 /* random streams are derived from it (default 1) */
} duet_partial_sim_settings;

DUET_API void duet_partial_sim_settings_init(duet_partial_sim_settings* settings);

/* The combined strategy (Fig. 6): the simulated goal is taken if its reward R_g > eps_r_bits,
 * else the frontier search decides. */
typedef struct duet_exploration_settings {
  duet_partial_sim_settings simulation;
  duet_frontier_settings frontier;
  float eps_r_bits;     /* eps_R [bits], finite, >= 0 (default 1.0; R_g counts re-seen cells too, the paper's test) */
  int use_simulation;   /* 1 = Fig. 6; 0 = frontier search only (explore_lite-like) (default 1) */
} duet_exploration_settings;

DUET_API void duet_exploration_settings_init(duet_exploration_settings* settings);

/* What the chassis can do (paper §4.1: a Kobuki, 0.5 m/s while exploring). */
typedef struct duet_chassis_limits {
  float max_v_mps;      /* forward speed limit, > 0 [m/s] (default 0.5) */
  float min_v_mps;      /* reverse speed limit, <= 0 [m/s] (default -0.2) */
  float max_omega_rps;  /* |omega| limit, > 0 [rad/s] (default pi: 180 deg/s) */
  float max_accel_mps2; /* |dv/dt| limit, > 0 [m/s^2] (default 1.0) */
  float max_alpha_rps2; /* |domega/dt| limit, > 0 [rad/s^2] (default 3.0) */
} duet_chassis_limits;

/* Dynamic window (Fox et al. 1997) following a path, with the paper's motion constraint
 * (|omega| and |domega/dt| bounded while mapping) and a recovery (rotate in place, back off).
 * Ranges as the C++ kernel (dwa.hpp) checks them. */
typedef struct duet_dwa_settings {
  duet_chassis_limits limits;
  float mapping_max_omega_rps;    /* (0, inf) [rad/s] (default 0.8) */
  float mapping_max_alpha_rps2;   /* (0, inf) [rad/s^2] (default 1.0) */
  float control_period_s;         /* (0, 10] [s] (default 0.05: 20 Hz) */
  int v_samples, omega_samples;   /* [1, 1000] each (default 20, 40) */
  int steps;                      /* rollout steps, [1, 1000] (default 30) */
  float sim_time_s;               /* rollout horizon, (0, 60] [s] (default 1.5) */
  float robot_radius_m;           /* footprint radius, >= 0 [m] (default 0.20) */
  float safety_margin_m;          /* extra clearance, >= 0 [m] (default 0.02) */
  float w_progress, w_path, w_clearance, w_speed; /* score weights, >= 0 (default 1.0, 0.5, 0.3, 0.1) */
  float clearance_cap_m;          /* >= 0 [m] (default 0.30) */
  float lookahead_m;              /* > 0 [m] (default 1.0) */
  float goal_tolerance_m;         /* >= 0 [m] (default 0.15) */
  int oscillation_window_calls;   /* [1, 1e6] (default 60) */
  float oscillation_min_progress_m; /* >= 0 [m] (default 0.10) */
  float oscillation_min_turn_rad; /* [0, pi] [rad] (default 0.5) */
  int recovery_max_calls;         /* [1, 1e6] (default 60) */
  float rotate_omega_rps;         /* > 0 [rad/s] (default 0.6) */
  float rotate_tolerance_rad;     /* [0, pi] [rad] (default 0.35) */
  float backoff_distance_m;       /* [0, 10] [m] (default 0.15) */
  float backoff_speed_mps;        /* > 0 [m/s] (default 0.1) */
} duet_dwa_settings;

DUET_API void duet_dwa_settings_init(duet_dwa_settings* settings);

/* ---- status codes (each with a static name string, "DUET_..._?" for other values) -------- */

enum duet_path_status {
  DUET_PATH_FOUND = 0,         /* the waypoints hold a path */
  DUET_PATH_START_BLOCKED = 1, /* no traversable cell within robot_radius_m of the start cell */
  DUET_PATH_GOAL_BLOCKED = 2,  /* goal cell (or every cell within goal_tolerance_m) not traversable */
  DUET_PATH_NO_PATH = 3,       /* start and goal in different traversable components */
  DUET_PATH_OUTSIDE_GRID = 4   /* start or goal outside the grid */
};

enum duet_frontier_status {
  DUET_FRONTIER_FOUND = 0,           /* goal and path are set */
  DUET_FRONTIER_NO_FRONTIER = 1,     /* no frontier left: exploration is complete */
  DUET_FRONTIER_ALL_UNREACHABLE = 2, /* frontiers exist, none reachable */
  DUET_FRONTIER_ALL_BLACKLISTED = 3, /* reachable frontiers are all blacklisted or too near */
  DUET_FRONTIER_ROBOT_BLOCKED = 4    /* robot outside the grid or in an inflated obstacle */
};

enum duet_exploration_status {
  DUET_EXPLORATION_SIMULATED_GOAL = 0,  /* R_g > eps_R: the partial map simulation's goal */
  DUET_EXPLORATION_FRONTIER_GOAL = 1,   /* the nearest reachable, non-blacklisted frontier */
  DUET_EXPLORATION_NO_FRONTIER = 2,     /* nothing left to explore */
  DUET_EXPLORATION_ALL_UNREACHABLE = 3, /* frontiers exist but none can be reached */
  DUET_EXPLORATION_ALL_BLACKLISTED = 4, /* every reachable frontier is blacklisted or too near */
  DUET_EXPLORATION_ROBOT_BLOCKED = 5    /* no traversable cell near the robot */
};

enum duet_dwa_status {
  DUET_DWA_OK = 0,                  /* best admissible trajectory's command */
  DUET_DWA_GOAL_REACHED = 1,        /* within goal_tolerance_m of the path's end; zero command */
  DUET_DWA_ROTATE_IN_PLACE = 2,     /* recovery: rotating toward the path */
  DUET_DWA_BACK_OFF = 3,            /* recovery: straight reverse */
  DUET_DWA_NO_VALID_TRAJECTORY = 4, /* nothing admissible, no recovery possible; zero command */
  DUET_DWA_NO_PATH = 5              /* empty path; zero command */
};

DUET_API const char* duet_path_status_string(enum duet_path_status status);
DUET_API const char* duet_frontier_status_string(enum duet_frontier_status status);
DUET_API const char* duet_exploration_status_string(enum duet_exploration_status status);
DUET_API const char* duet_dwa_status_string(enum duet_dwa_status status);

/* ---- results ------------------------------------------------------------------------------ */

/* One ray of one sensor at one pose (duet_planner_observe). */
typedef struct duet_ray_observation {
  float entropy_bits; /* entropy summed over the cells crossed from min_range to the hit (hit
                         cell included) or to max_range [bits] */
  float range_m;      /* where the ray stopped, from the sensor origin [m] */
  int32_t hit;        /* 1 = stopped at an occupied cell, 0 = reached max_range */
  int32_t cells;      /* cells summed */
} duet_ray_observation;

typedef struct duet_partial_sim_result {
  int found;                /* 1: a valid particle with a positive reward exists */
  duet_pose2 goal;          /* X_g (the robot's pose when found = 0) */
  float reward_bits;        /* R_g: expected entropy reduction at X_g [bits] (0 when not found) */
  int best_particle;        /* n_m (-1 if none) */
  int valid_particles;      /* non-rejected rollouts in the last iteration */
  int resamples;            /* iterations that resampled */
  int64_t cells_visited;    /* cells processed by the simulated observations (diagnostics) */
  size_t trajectory_count;  /* full length of X_{1:H} of n_m (H, or 0) */
} duet_partial_sim_result;

typedef struct duet_frontier_cluster {
  int32_t cells;               /* frontier cells in the cluster */
  float centroid_x, centroid_y; /* mean of the cell centres [m] */
  float nearest_x, nearest_y;  /* reachable: its nearest reached cell; else the cell nearest (Euclidean) to the robot [m] */
  float path_length_m;         /* path length from the robot to nearest [m]; +inf if unreachable */
  int reachable;               /* 1 if the search reached one of its cells */
  int blacklisted;             /* 1 if reachable but offers no goal because of the blacklist */
} duet_frontier_cluster;

typedef struct duet_frontier_result {
  enum duet_frontier_status status;
  float goal_x, goal_y;    /* centre of the goal cell [m] (DUET_FRONTIER_FOUND only, else 0) */
  float path_length_m;     /* path length to the goal [m] (DUET_FRONTIER_FOUND only, else 0) */
  size_t path_count;       /* full number of path points (robot cell first, goal cell last) */
  size_t cluster_count;    /* full number of kept clusters (ordered by their smallest cell index) */
  size_t frontier_cells;   /* frontier cells in kept clusters */
  size_t reached_cells;    /* cells settled by the search (diagnostics) */
  float target_x, target_y; /* the frontier cell the goal is for [m]: the goal itself, or for a goal
                               on an approach cell (approach_radius_m) its source frontier cell */
} duet_frontier_result;

/* One decision of Fig. 6. `simulation` and `frontier` report the two stages (their arrays are
 * not returned here: their counts are informative; call duet_planner_simulate /
 * duet_planner_find_frontier for the arrays). */
typedef struct duet_decision {
  enum duet_exploration_status status;
  duet_pose2 goal;                    /* valid for SIMULATED_GOAL and FRONTIER_GOAL (a frontier
                                         goal faces along the last path segment); else the
                                         robot's pose */
  float reward_bits;                  /* R_g of the simulation (also when the frontier won) */
  int simulated_goal_blacklisted;     /* 1: R_g > eps_R but X_g lies in a blacklisted area */
  int simulation_ran;                 /* 1 if use_simulation (then `simulation` is set) */
  int frontier_ran;                   /* 1 if the frontier search ran (then `frontier` is set) */
  duet_partial_sim_result simulation; /* when simulation_ran = 0: found 0, goal 0, best_particle
                                         -1, other fields 0 */
  duet_frontier_result frontier;      /* when frontier_ran = 0: status NO_FRONTIER, other fields 0 */
} duet_decision;

typedef struct duet_path_result {
  enum duet_path_status status;
  size_t waypoint_count; /* full number of waypoints (cell centres, start to goal; 0 unless FOUND) */
  float length_m;        /* polyline length [m] (0 unless FOUND) */
  float cost;            /* clearance-weighted cost [m], >= length_m */
  int start_moved;       /* 1: the start cell was not traversable; waypoint 0 is the nearest
                            traversable cell within robot_radius_m */
  size_t expanded;       /* cells expanded by the search (diagnostics) */
} duet_path_result;

typedef struct duet_dwa_result {
  enum duet_dwa_status status;
  duet_twist cmd;              /* command to send [m/s, rad/s] */
  float score;                 /* score of the chosen trajectory (DUET_DWA_OK), else -inf */
  int valid_trajectories;      /* admissible trajectories this call */
  int evaluated_trajectories;  /* trajectories rolled out this call */
  int oscillation;             /* 1: a recovery started this call because of an oscillation */
  float lookahead_x, lookahead_y; /* the lookahead point on the path [m] */
} duet_dwa_result;

/* ---- the planner ------------------------------------------------------------------------ */

/* Creates a planner with no grid, the default sensors (duet_paper_dual_sensors(out, 30)), an
 * empty blacklist and a reset dynamic window. Ownership: the caller owns the returned
 * reference; the planner keeps a reference to `device`. Thread-safe. */
DUET_API duet_planner duet_planner_new(duet_device device);
DUET_API void duet_planner_retain(duet_planner planner);
DUET_API void duet_planner_release(duet_planner planner);

/* Replaces the sensors by a copy of `count` sectors (1 to 1000, at most 1000000 rays in all),
 * each validated (the message names sensors[i] and the field). On error the sensors are
 * unchanged. Serialized on the planner. */
DUET_API void duet_planner_set_sensors(duet_planner planner, const duet_sensor_sector* sensors,
                                       size_t count);

/* Copies min(count, capacity) sensors to `out` and returns the full count (0 on error).
 * Serialized on the planner. */
DUET_API size_t duet_planner_get_sensors(duet_planner planner, duet_sensor_sector* out,
                                         size_t capacity);

/* Total rays of all sensors (the per-pose row length of duet_planner_observe); 0 on error.
 * Serialized on the planner. */
DUET_API size_t duet_planner_get_ray_count(duet_planner planner);

/* Sets the planner's map from a caller buffer: `height` rows of `width` float log-odds (NaN =
 * unknown), row 0 at the lowest y, rows `row_stride_bytes` apart (0 = packed = width * 4; else
 * a multiple of 4, >= width * 4; `logodds` 4-byte aligned). width, height > 0 with
 * width * height < 2^30 (else DUET_ERROR_OUT_OF_RANGE); resolution_m in [0.001, 100] (the map
 * frame's cells, as duet_grid_new); origin (world position of cell (0, 0)'s lower-left corner
 * [m]) finite, within +-20 km (else DUET_ERROR_OUT_OF_RANGE).
 * The planner COPIES the cells (the observation model owns its copy; the buffer may be reused
 * or freed when the call returns). With the same geometry (size, resolution, origin) and the
 * same observation settings as the previous successful call the observation model is updated
 * incrementally (only the Embree tiles whose occupied cells changed are rebuilt), else it is
 * rebuilt; the grid is then inflated. The results equal those of a fresh planner either way.
 * Settings NULL = defaults. Errors in the arguments and settings leave the planner unchanged;
 * an error inside the kernels (out of memory, Embree) leaves it without a grid.
 * Serialized on the planner. */
DUET_API void duet_planner_set_grid(duet_planner planner, const float* logodds,
                                    size_t row_stride_bytes, int width, int height,
                                    float resolution_m, float origin_x, float origin_y,
                                    const duet_observation_settings* observation_settings,
                                    const duet_inflation_settings* inflation_settings);

/* The same from a duet_grid of the same device (else DUET_ERROR_INVALID_OPERATION) that is not
 * empty (else DUET_ERROR_INVALID_ARGUMENT): its log-odds, geometry and origin are copied under
 * a shared lock on the grid. Serialized on the planner; shared on `grid`. */
DUET_API void duet_planner_set_grid_from(duet_planner planner, duet_grid grid,
                                         const duet_observation_settings* observation_settings,
                                         const duet_inflation_settings* inflation_settings);

/* Size of the planner's grid in cells; 0 x 0 before the first successful set_grid (not an
 * error). Either pointer may be NULL. On error both are set to 0. Serialized on the planner. */
DUET_API void duet_planner_get_grid_size(duet_planner planner, int* width, int* height);

/* Copies, row-major, into a caller buffer of exactly `count` = width * height elements (else
 * DUET_ERROR_INVALID_ARGUMENT naming the expected and the given count):
 *   clearance:     distance from each cell's centre to the nearest blocked cell's centre [m]
 *                  (0 for blocked cells, +inf when no cell is blocked)
 *   traversable:   1 iff the cell is free and its clearance > the inflation's robot_radius_m
 *   frontier_mask: 1 iff the cell is free with an unknown 8-neighbour inside the grid (raw
 *                  frontier cells: no cluster-size filter, border cells included)
 * Serialized on the planner. */
DUET_API void duet_planner_copy_clearance(duet_planner planner, float* out, size_t count);
DUET_API void duet_planner_copy_traversable(duet_planner planner, uint8_t* out, size_t count);
DUET_API void duet_planner_copy_frontier_mask(duet_planner planner, uint8_t* out, size_t count);

/* Observation model (paper §3.1) at `count` robot poses: out[p * R + r] (R =
 * duet_planner_get_ray_count(), rays ordered sensor by sensor) receives ray r at pose p, walked
 * over [min_range_m, max_range_m] of its sensor. A known obstacle in a cell the ray leaves at or
 * before min_range_m blocks the ray (no depth below the minimum range): entropy 0, cells 0,
 * hit 1, range_m = the entry distance of that cell. out_count must be count * R (else
 * DUET_ERROR_INVALID_ARGUMENT). Serialized on the planner. */
DUET_API void duet_planner_observe(duet_planner planner, const duet_pose2* poses, size_t count,
                                   duet_ray_observation* out, size_t out_count);

/* Sum of entropy_bits over all rays of all sensors at `pose` [bits] (the paper's ray-tracing
 * information of a pose; a cell crossed by k rays counts k times). 0 on error.
 * Serialized on the planner. */
DUET_API float duet_planner_information(duet_planner planner, duet_pose2 pose);

/* Partial map simulation (Procedure 1) from `robot`: *out receives the goal X_g and its reward;
 * `trajectory` receives min(trajectory_capacity, out->trajectory_count) poses X_1..X_H of the
 * best particle (see the capacity rule above). Serialized on the planner. */
DUET_API void duet_planner_simulate(duet_planner planner, duet_pose2 robot,
                                    const duet_partial_sim_settings* settings,
                                    duet_partial_sim_result* out, duet_pose2* trajectory,
                                    size_t trajectory_capacity);

/* Global frontier search from the robot's position (x, y) [m], with the planner's blacklist at
 * the caller's time now_s [s]. path_xy receives min(path_capacity, out->path_count) points as
 * x, y float pairs (2 * path_capacity floats), clusters min(cluster_capacity,
 * out->cluster_count) clusters (see the capacity rule above). Serialized on the planner. */
DUET_API void duet_planner_find_frontier(duet_planner planner, float x, float y, double now_s,
                                         const duet_frontier_settings* settings,
                                         duet_frontier_result* out, float* path_xy,
                                         size_t path_capacity, duet_frontier_cluster* clusters,
                                         size_t cluster_capacity);

/* The goal blacklist (used by find_frontier and decide): add blocks frontier goals within the
 * frontier settings' blacklist_radius_m of (x, y) [m] while now_s < expiry = now_s + ttl_s
 * (ttl_s > 0, +inf = forever; x, y, now_s finite); expire removes the entries expired at now_s;
 * clear removes all; get_size counts the stored entries, expired ones not yet removed
 * included (0 on error). Need no grid. Serialized on the planner. */
DUET_API void duet_planner_blacklist_add(duet_planner planner, float x, float y, double now_s,
                                         double ttl_s);
DUET_API void duet_planner_blacklist_expire(duet_planner planner, double now_s);
DUET_API void duet_planner_blacklist_clear(duet_planner planner);
DUET_API size_t duet_planner_blacklist_get_size(duet_planner planner);

/* One exploration decision (Fig. 6) for the robot at `robot` at the caller's time now_s [s].
 * Serialized on the planner. */
DUET_API void duet_planner_decide(duet_planner planner, duet_pose2 robot, double now_s,
                                  const duet_exploration_settings* settings, duet_decision* out);

/* Global path from (start_x, start_y) to (goal_x, goal_y) [m] on the inflated grid: *out
 * receives the status and the full waypoint count, xy min(capacity, out->waypoint_count)
 * waypoints as x, y float pairs (2 * capacity floats). Serialized on the planner. */
DUET_API void duet_planner_plan_path(duet_planner planner, float start_x, float start_y,
                                     float goal_x, float goal_y,
                                     const duet_path_settings* settings, duet_path_result* out,
                                     float* xy, size_t capacity);

/* One control step of the dynamic window at `pose` with the chassis' present twist `current`
 * (odometry), following the polyline of `path_count` waypoints (x, y float pairs at byte stride
 * path_stride, 0 = packed = 8, read in place; path_count 0 -> DUET_DWA_NO_PATH), on the
 * planner's clearance (a trajectory is admissible iff the clearance along it stays >
 * settings.robot_radius_m + safety_margin_m). Uses and updates the planner's dynamic window
 * state (oscillation detection, recovery phase); on error the state is unchanged.
 * Serialized on the planner. */
DUET_API void duet_planner_dwa_step(duet_planner planner, duet_pose2 pose, duet_twist current,
                                    const float* path_xy, size_t path_stride, size_t path_count,
                                    const duet_dwa_settings* settings, duet_dwa_result* out);

/* Resets the dynamic window state (e.g. when a new goal is sent). Needs no grid.
 * Serialized on the planner. */
DUET_API void duet_planner_dwa_reset(duet_planner planner);

#ifdef __cplusplus
} /* extern "C" */
#endif

#endif /* DUET_PLANNER_H */
