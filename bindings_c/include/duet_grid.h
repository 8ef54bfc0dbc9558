/*
 * duet_grid.h - the 2D log-odds occupancy grid in the C API of duet: creation, updates from
 * labelled points, getters, copies (log-odds, probabilities, ROS values), map_server files.
 * Part of duet.h: include duet.h, not this file directly. The conventions at the top of
 * duet.h (handles, errors, buffers, settings, thread safety, frames) hold here.
 */
#include "duet.h" /* before the guard: alone, this file then declares all of duet.h in order */
#ifndef DUET_GRID_H
#define DUET_GRID_H

#ifdef __cplusplus
extern "C" {
#endif

/* ============================================================================================
 * Occupancy grid: 2D log-odds grid in the x-y plane of the map frame. Cell (ix, iy) covers
 * [origin_x + ix*res, origin_x + (ix+1)*res) x [origin_y + iy*res, ...); storage row-major,
 * row 0 at the lowest y. Never-observed cells hold NaN log-odds ("unknown"). The grid starts
 * empty (0 x 0) and grows (never shrinks) to contain the data of each update.
 * ========================================================================================== */

/* Creates an empty grid of cells `resolution_m` [m] wide, in [0.001, 100] (else NULL,
 * DUET_ERROR_INVALID_ARGUMENT). Ownership: the caller owns the returned reference; the grid
 * keeps a reference to `device`. Thread-safe.
 * Coordinates: the map frame reaches +-10 km from its origin (a float still resolves 1 mm
 * there); a sensor beyond it is DUET_ERROR_OUT_OF_RANGE, points beyond it are skipped. */
DUET_API duet_grid duet_grid_new(duet_device device, float resolution_m);
DUET_API void duet_grid_retain(duet_grid grid);
DUET_API void duet_grid_release(duet_grid grid);

typedef struct duet_grid_update_settings {
  float hit_logodds;      /* added to a cell hit by an obstacle point (default 0.85) */
  float miss_logodds;     /* added to a cell seen free (default -0.4) */
  float min_logodds;      /* clamp (default -2.0) */
  float max_logodds;      /* clamp (default 3.5) */
  int clear_along_rays;   /* 1 = cells crossed by each sensor ray are free (default 1), 0 = no */
  float max_ray_length_m; /* hits farther from the sensor are ignored [m] (default 8.0) */
  int grow_margin_cells;  /* growth step around new data [cells] (default 40) */
} duet_grid_update_settings;

DUET_API void duet_grid_update_settings_init(duet_grid_update_settings* settings);

/* Integrates one scan seen from a sensor at (sensor_x, sensor_y) [m]: obstacle points mark
 * their cells occupied, floor points free, and (clear_along_rays) every cell on the 2D ray
 * from the sensor to each such point's cell is free; at most one update per cell and call.
 * labels (count uint8 at labels_stride) hold enum duet_point_label values (others ->
 * DUET_ERROR_INVALID_ARGUMENT); ignored and non-finite points, and points beyond +-10 km,
 * are skipped. A sensor beyond +-10 km, or growing beyond 2^28 cells -> DUET_ERROR_OUT_OF_RANGE. Errors found before the update starts (handles,
 * buffers, labels, settings) leave the grid unchanged; a kernel error leaves it valid.
 * Thread-safe (exclusive on `grid`). */
DUET_API void duet_grid_update(duet_grid grid, float sensor_x, float sensor_y, const float* xyz,
                               size_t xyz_stride, const uint8_t* labels, size_t labels_stride,
                               size_t count, const duet_grid_update_settings* settings);

/* Size in cells, cell edge [m], world position of cell (0,0)'s corner [m], number of cells
 * observed at least once. 0 on error (origin untouched on error). Thread-safe. */
DUET_API int duet_grid_get_width(duet_grid grid);
DUET_API int duet_grid_get_height(duet_grid grid);
DUET_API float duet_grid_get_resolution(duet_grid grid);
DUET_API void duet_grid_get_origin(duet_grid grid, float* origin_x, float* origin_y);
DUET_API size_t duet_grid_get_known_cells(duet_grid grid);

/* Copy the grid, row-major, into a caller buffer of exactly `count` = width * height
 * elements (else DUET_ERROR_INVALID_ARGUMENT naming the expected and the given count):
 *   logodds:        clamped log-odds, NaN = unknown
 *   probabilities:  occupancy probability 1 - 1/(1 + exp(l)), -1 = unknown
 *   ros:            nav_msgs/OccupancyGrid values: 100 occupied (p >= occupied_threshold),
 *                   0 free (p <= free_threshold), -1 unknown or in between; thresholds in
 *                   [0, 1] with free_threshold <= occupied_threshold. duet's own exports use
 *                   0.65 and 0.45: one hit (p 0.70) is occupied, one miss (p 0.40) free.
 * Thread-safe. */
DUET_API void duet_grid_copy_logodds(duet_grid grid, float* out, size_t count);
DUET_API void duet_grid_copy_probabilities(duet_grid grid, float* out, size_t count);
DUET_API void duet_grid_copy_ros(duet_grid grid, int8_t* out, size_t count,
                                 float occupied_threshold, float free_threshold);

/* A ROS map_server map (its YAML and the image it names: trinary, scale or raw modes, negate,
 * thresholds) as a new grid on `device`: occupied pixels get log-odds 3.5, free -2.0 (the
 * grid update's clamps: as certain as a map gets), unknown NaN, in-between values of the
 * scale and raw modes their probability's log-odds; origin and resolution from the YAML. Errors name the file
 * (IO: missing, not a regular file or too large; PARSE: malformed YAML or image). Returns NULL
 * on error. Thread-safe. */
DUET_API duet_grid duet_grid_load_map_server(duet_device device, const char* yaml_path);

/* Writes `grid` as a map_server map: `yaml_path` and a trinary PGM beside it (same stem, .pgm;
 * occupied p >= 0.65, free p <= 0.45, else unknown), each written under a temporary name and
 * renamed. IO error naming the file when it cannot be written. Thread-safe (shared on grid). */
DUET_API void duet_grid_save_map_server(duet_grid grid, const char* yaml_path);

#ifdef __cplusplus
} /* extern "C" */
#endif

#endif /* DUET_GRID_H */
