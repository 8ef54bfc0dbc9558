/*
 * duet.h - the C API of duet (libduet.so), version 1.
 *
 * Modelled on Embree's C API (rtcore_device.h): opaque reference-counted handles created by a
 * device, errors reported through the device instead of return codes, caller buffers passed
 * as (pointer, byte stride, count).
 *
 * ---------------------------------------------------------------------------------------------
 * Handles
 *   duet_device  owns the TBB task arena (every kernel runs inside it) and the error state.
 *   duet_cloud   a point cloud (positions, optional colours, normals, curvature) owned by duet.
 *   duet_grid    a 2D log-odds occupancy grid owned by duet.
 *   Every handle starts with one reference; *_retain adds one, *_release drops one, the object
 *   is destroyed when the last reference is dropped. Clouds and grids hold a reference to the
 *   device that created them, so a device stays valid until its last cloud/grid is released
 *   (as in Embree). Handles are opaque tokens, never dereference them.
 *
 * Handle validation
 *   Every call checks every handle against a process-wide registry of live handles before
 *   touching it:
 *     NULL handle                                   -> DUET_ERROR_INVALID_ARGUMENT
 *     released handle, or a handle of another type   -> DUET_ERROR_INVALID_OPERATION
 *   A released handle is detected without reading freed memory and is never recycled, so a
 *   stale handle can never silently refer to a newer object.
 *
 * Errors
 *   No function returns an error code. Each device keeps the FIRST error that happened since
 *   the last duet_device_get_error() (get-and-clear), the message of the LAST error, and an
 *   optional callback that is called synchronously for every error. Errors that have no usable
 *   device (NULL or released device handle, a failed duet_device_new, a NULL/dead cloud or grid
 *   handle whose device cannot be known) go to a thread-local "no device" slot read with
 *   duet_device_get_error(NULL) / duet_device_get_error_message(NULL). A function that fails
 *   leaves its outputs unchanged (clouds, grids and caller buffers) unless stated otherwise and
 *   returns NULL / 0 when it returns a value. No C++ exception ever crosses this API.
 *
 * Buffers
 *   Inputs are read in place, never copied, unless stated. A buffer is (pointer, byte stride,
 *   count); stride 0 means tightly packed (12 bytes for xyz/normals, 3 for rgb, 4 for float and
 *   uint32, 1 for uint8). Float and uint32 buffers must be 4-byte aligned with a stride that
 *   is a multiple of 4. count 0 is valid (pointer may then be NULL); a NULL pointer with a
 *   non-zero count is DUET_ERROR_INVALID_ARGUMENT. Outputs with a per-point layout hold `count`
 *   elements (the count of the input points of the same call); outputs whose size duet decides
 *   (grid copies, cloud copies) take the caller's element count and fail with
 *   DUET_ERROR_INVALID_ARGUMENT naming the expected and the given count when they differ.
 *   Outputs may overlap inputs: results are computed first and written last.
 *
 * Settings
 *   Every settings struct mirrors the C++ kernel's settings. Fill it with the matching
 *   duet_*_settings_init() (C has no default member values), change what you need, and pass
 *   its address; passing NULL uses the defaults. Every field is validated on use
 *   (DUET_ERROR_INVALID_ARGUMENT naming the field). Settings layouts change only with
 *   DUET_VERSION_MAJOR (the library's SONAME), so they carry no size field.
 *
 * Thread safety
 *   All functions may be called from any thread. Device functions are thread-safe. Functions on
 *   a cloud or grid are thread-safe: calls on the same object are serialized internally
 *   (modifying calls exclusively, getters concurrently), calls on distinct objects run in
 *   parallel (inside the shared device arena). Pointers borrowed with duet_cloud_get_*() are
 *   invalidated by any later call that modifies that cloud; coordinate that yourself.
 *   Results never depend on the device's thread count.
 *
 * Frames and units (DESIGN.md §6)
 *   SI units (metres, radians unless a name says _deg). Robot frame: x forward, y left, z up.
 *   Camera optical frame: z forward, x right, y down. A transform T_a_b maps b coordinates
 *   into a coordinates. Matrices are 4x4, column-major float[16] (OpenGL / Eigen layout:
 *   element (row r, column c) is m[c * 4 + r]; the translation is m[12], m[13], m[14]).
 */
#ifndef DUET_H
#define DUET_H

#include <stddef.h>
#include <stdint.h>

#include "duet_version.h"

#if defined(_WIN32)
#  if defined(DUET_BUILDING_LIBRARY)
#    define DUET_API __declspec(dllexport)
#  else
#    define DUET_API __declspec(dllimport)
#  endif
#else
#  define DUET_API __attribute__((visibility("default")))
#endif

#ifdef __cplusplus
extern "C" {
#endif

/* ============================================================================================
 * Version
 * ========================================================================================== */

/* DUET_VERSION of the library actually loaded (compare with the DUET_VERSION macro of the
 * header you compiled against). Thread-safe. */
DUET_API int duet_get_version(void);

/* "MAJOR.MINOR.PATCH" of the loaded library; static storage, never freed. Thread-safe. */
DUET_API const char* duet_get_version_string(void);

/* ============================================================================================
 * Handles and errors
 * ========================================================================================== */

typedef struct duet_device_t* duet_device;
typedef struct duet_cloud_t* duet_cloud;
typedef struct duet_grid_t* duet_grid;

enum duet_error {
  DUET_ERROR_NONE = 0,
  DUET_ERROR_INVALID_ARGUMENT = 1,  /* NULL handle or pointer, bad size/stride/setting/value */
  DUET_ERROR_INVALID_OPERATION = 2, /* released handle, or a handle of another type */
  DUET_ERROR_OUT_OF_RANGE = 3,      /* input data the kernel cannot represent (index overflow) */
  DUET_ERROR_IO = 4,                /* a file could not be read or written */
  DUET_ERROR_PARSE = 5,             /* a file or configuration is malformed */
  DUET_ERROR_UNSUPPORTED = 6,       /* a valid request duet does not implement */
  DUET_ERROR_OUT_OF_MEMORY = 7,     /* an allocation failed */
  DUET_ERROR_UNKNOWN = 8            /* anything else (an internal error of duet) */
};

/* Called synchronously, on the thread that made the failing call, before that call returns.
 * `message` is valid only during the callback. The callback must not throw (C++); it may call
 * duet functions, including on the same device. */
typedef void (*duet_error_callback)(void* user_ptr, enum duet_error code, const char* message);

/* Static name of an error code ("DUET_ERROR_INVALID_ARGUMENT"); "DUET_ERROR_?" for others. */
DUET_API const char* duet_error_string(enum duet_error code);

/* ============================================================================================
 * Device
 * ========================================================================================== */

/* Creates a device from a configuration string of comma-separated key=value pairs
 * (whitespace around tokens ignored; NULL or "" = all defaults):
 *   threads=N   threads of the device's task arena (the calling thread included), in
 *               [0, 1024]; 0 = all cores (default 0); values above the number of cores TBB
 *               may use are clamped to it
 *   verbose=V   0 = silent (default), 1 = also print every error to stderr
 * An unknown key, a repeated key, a missing '=' or a bad value returns NULL and records
 * DUET_ERROR_INVALID_ARGUMENT with a message naming the key in the no-device slot
 * (duet_device_get_error(NULL), duet_device_get_error_message(NULL)).
 * Ownership: the caller owns the returned reference. Thread-safe. */
DUET_API duet_device duet_device_new(const char* config);

/* Adds / drops a reference. The device is destroyed when its last reference is dropped; each
 * live cloud and grid holds one, so releasing the device while they live only drops the
 * caller's reference (the handle stays valid until they are released too). Thread-safe. */
DUET_API void duet_device_retain(duet_device device);
DUET_API void duet_device_release(duet_device device);

/* Number of threads of the device's arena (>= 1). 0 on error. Thread-safe. */
DUET_API int duet_device_get_thread_count(duet_device device);

/* Returns the first error recorded on `device` since the previous call and clears it
 * (DUET_ERROR_NONE if none). The slot is per device and shared by all threads using it
 * (Embree keeps one per thread). device == NULL reads and clears this thread's no-device slot.
 * For a released device returns DUET_ERROR_INVALID_OPERATION (and sets the no-device message).
 * Thread-safe. */
DUET_API enum duet_error duet_device_get_error(duet_device device);

/* Message of the last error recorded on `device` (NULL: this thread's no-device slot), ""
 * if there was none. Not cleared by duet_device_get_error(). The returned string is owned by
 * duet and valid until the next duet_device_get_error_message() call on the same thread.
 * Thread-safe. */
DUET_API const char* duet_device_get_error_message(duet_device device);

/* Sets (callback != NULL) or removes (callback == NULL) the error callback of `device`.
 * device == NULL sets the process-wide callback of the no-device slot.
 * `user_ptr` is passed back unchanged; the caller keeps ownership. Thread-safe. */
DUET_API void duet_device_set_error_callback(duet_device device, duet_error_callback callback,
                                             void* user_ptr);

/* ============================================================================================
 * Cloud
 * ========================================================================================== */

/* Creates an empty cloud. Ownership: the caller owns the returned reference; the cloud keeps
 * a reference to `device`. Thread-safe. */
DUET_API duet_cloud duet_cloud_new(duet_device device);
DUET_API void duet_cloud_retain(duet_cloud cloud);
DUET_API void duet_cloud_release(duet_cloud cloud);

/* Replaces the cloud's contents by a copy of `count` points (and colours if rgb != NULL);
 * normals and curvature are cleared. Thread-safe (exclusive on the cloud). */
DUET_API void duet_cloud_set_points(duet_cloud cloud, const float* xyz, size_t xyz_stride,
                                    const uint8_t* rgb, size_t rgb_stride, size_t count);

/* Removes every point and attribute. Thread-safe (exclusive on the cloud). */
DUET_API void duet_cloud_clear(duet_cloud cloud);

/* Number of points; 0 on error. Thread-safe. */
DUET_API size_t duet_cloud_get_size(duet_cloud cloud);
/* 1 if the cloud has colours / normals (and curvature), else 0 (also on error). Thread-safe. */
DUET_API int duet_cloud_has_colors(duet_cloud cloud);
DUET_API int duet_cloud_has_normals(duet_cloud cloud);

/* Borrow the cloud's storage without copying. *ptr receives the first element (NULL when the
 * cloud is empty or lacks the attribute), *stride (if stride != NULL) its byte stride (12 for
 * points and normals, 3 for colours r,g,b, 4 for curvature); ptr must not be NULL. Ownership stays with the cloud: the pointer is valid
 * until the cloud is next modified or destroyed. Normals and curvature are NaN where
 * undefined. On error *ptr = NULL and *stride = 0 (when those pointers are not NULL).
 * Thread-safe. */
DUET_API void duet_cloud_get_points(duet_cloud cloud, const float** ptr, size_t* stride);
DUET_API void duet_cloud_get_colors(duet_cloud cloud, const uint8_t** ptr, size_t* stride);
DUET_API void duet_cloud_get_normals(duet_cloud cloud, const float** ptr, size_t* stride);
DUET_API void duet_cloud_get_curvature(duet_cloud cloud, const float** ptr, size_t* stride);

/* Copy the cloud's attributes into caller memory at the caller's stride. `count` must equal
 * duet_cloud_get_size() (else DUET_ERROR_INVALID_ARGUMENT naming both); copying a missing
 * attribute of a non-empty cloud is DUET_ERROR_INVALID_OPERATION. Thread-safe. */
DUET_API void duet_cloud_copy_points(duet_cloud cloud, float* xyz, size_t stride, size_t count);
DUET_API void duet_cloud_copy_colors(duet_cloud cloud, uint8_t* rgb, size_t stride, size_t count);
DUET_API void duet_cloud_copy_normals(duet_cloud cloud, float* normals, size_t stride,
                                      size_t count);
DUET_API void duet_cloud_copy_curvature(duet_cloud cloud, float* curvature, size_t stride,
                                        size_t count);

/* ============================================================================================
 * Back-projection (paper §2.1, Eq. (6)): depth images of several sensors -> one cloud in the
 * robot frame. Pinhole: p_cam = d * ((u - cx) / fx, (v - cy) / fy, 1),
 * p_robot = T_robot_camera * p_cam. Pixels with depth 0, NaN, inf or outside
 * [min_depth_m, max_depth_m] are dropped. Output order: sensor by sensor, row-major.
 * ========================================================================================== */

enum duet_depth_format {
  DUET_DEPTH_U16 = 0, /* uint16 raw; metres = raw / depth_units_per_m (Kinect/TUM: 1000/5000) */
  DUET_DEPTH_F32 = 1  /* float metres */
};

typedef struct duet_sensor_frame {
  /* depth image (required), row-major, caller memory read in place */
  const void* depth;                  /* width * height pixels of depth_format */
  int width, height;                  /* [px], > 0 */
  size_t depth_row_stride;            /* bytes between rows, 0 = packed */
  enum duet_depth_format depth_format;
  float depth_units_per_m;            /* DUET_DEPTH_U16 only, > 0 (default 1000: millimetres) */

  /* colour image registered to the depth image (optional, same width x height) */
  const uint8_t* color;               /* NULL = no colour (points get white) */
  size_t color_row_stride;            /* bytes between rows, 0 = packed */
  int color_channels;                 /* 3 (RGB/BGR) or 4 (RGBA/BGRA), default 3 */
  int color_bgr;                      /* 1 = channel order B,G,R (OpenCV), default 0 */

  /* pinhole intrinsics [px] (default Kinect: 525, 525, 319.5, 239.5) */
  float fx, fy, cx, cy;

  /* camera optical frame -> robot frame, 4x4 column-major, rigid (rotation orthonormal
   * within 1e-3, last row 0 0 0 1). Default identity. See duet_camera_mount_matrix(). */
  float T_robot_camera[16];
} duet_sensor_frame;

/* Fills `frame` with defaults: no data, 640x480, DUET_DEPTH_U16 at 1000 units/m, no colour,
 * 3 channels RGB, Kinect intrinsics, identity transform. Thread-safe. */
DUET_API void duet_sensor_frame_init(duet_sensor_frame* frame);

/* T_robot_camera (column-major float[16]) of a camera whose body frame (x forward, y left,
 * z up) sits at (x, y, z) [m] in the robot frame, rotated by ZYX Euler angles (yaw about z,
 * then pitch about y, then roll about x) [rad], composed with the fixed body -> optical
 * rotation (optical z = body x, optical x = -body y, optical y = -body z). This is the
 * parameterisation of the paper's Eq. (6): sensor 1 = (-0.118, 0, 0.271, 0, 0, 0),
 * sensor 2 = (-0.118, 0, 0.481, -pi/2, 0, 0) (facing right). Does not need a device; a
 * NULL `out` is ignored. Thread-safe. */
DUET_API void duet_camera_mount_matrix(float x, float y, float z, float yaw, float pitch,
                                       float roll, float out[16]);

typedef struct duet_back_projection_settings {
  float min_depth_m; /* nearer returns are dropped [m] (default 0.5) */
  float max_depth_m; /* farther returns are dropped [m] (default 5.0) */
  int pixel_step;    /* use every n-th pixel in u and v, >= 1 (default 1) */
} duet_back_projection_settings;

DUET_API void duet_back_projection_settings_init(duet_back_projection_settings* settings);

/* Back-projects `frame_count` frames into `out` (replaced: points and colours filled,
 * normals and curvature cleared). If `sensor_offsets` is not NULL it receives
 * frame_count + 1 entries: the points of frame i are [offsets[i], offsets[i+1]).
 * Images are read in place. settings NULL = defaults. Errors go to out's device.
 * Thread-safe (exclusive on `out`). */
DUET_API void duet_back_project(duet_cloud out, const duet_sensor_frame* frames,
                                size_t frame_count,
                                const duet_back_projection_settings* settings,
                                size_t* sensor_offsets);

/* ============================================================================================
 * Voxel filter (paper §2.2, Fig. 4; pcl::VoxelGrid semantics): one point per occupied voxel at
 * the centroid of its points, with their mean colour; voxels ordered by z, y, x index.
 * Non-finite points are skipped. Coordinates whose voxel index overflows ->
 * DUET_ERROR_OUT_OF_RANGE (never a wrong result).
 * ========================================================================================== */

typedef struct duet_voxel_filter_settings {
  float leaf_size_m;             /* voxel edge [m], > 0 (default 0.05) */
  uint32_t min_points_per_voxel; /* voxels with fewer points are dropped (default 1) */
} duet_voxel_filter_settings;

DUET_API void duet_voxel_filter_settings_init(duet_voxel_filter_settings* settings);

/* Filters `count` points (xyz, read in place) and, if rgb != NULL, their colours into `out`
 * (replaced; colours filled only when given; normals and curvature cleared). The input may be
 * `out`'s own storage (duet_cloud_get_points). Errors go to out's device.
 * Thread-safe (exclusive on `out`). */
DUET_API void duet_voxel_filter(duet_cloud out, const float* xyz, size_t xyz_stride,
                                const uint8_t* rgb, size_t rgb_stride, size_t count,
                                const duet_voxel_filter_settings* settings);

/* ============================================================================================
 * Normals (paper §2.2, Eq. (2) corrected: eigenvector of the SMALLEST eigenvalue of the
 * covariance of the k nearest neighbours, the point included), flipped toward the viewpoint;
 * curvature = l0 / (l0 + l1 + l2). NaN for non-finite points or fewer than 3 neighbours.
 * ========================================================================================== */

typedef struct duet_normal_settings {
  int k;              /* neighbours including the point, >= 3 (default 10) */
  float viewpoint[3]; /* normals face this point [m] (default 0, 0, 0) */
} duet_normal_settings;

DUET_API void duet_normal_settings_init(duet_normal_settings* settings);

/* Computes normals and curvature of the cloud's points into the cloud (has_normals becomes 1).
 * Thread-safe (exclusive on `cloud`). */
DUET_API void duet_cloud_estimate_normals(duet_cloud cloud, const duet_normal_settings* settings);

/* Normals of `count` points (xyz, read in place) written to `normals` (count x 3 floats at
 * normals_stride) and, if `curvature` != NULL, curvature (count floats at curvature_stride).
 * Thread-safe: buffers are the caller's; errors go to `device`. */
DUET_API void duet_estimate_normals(duet_device device, const float* xyz, size_t xyz_stride,
                                    size_t count, const duet_normal_settings* settings,
                                    float* normals, size_t normals_stride, float* curvature,
                                    size_t curvature_stride);

/* ============================================================================================
 * Euclidean clustering (pcl::EuclideanClusterExtraction semantics): connected components of
 * "distance <= tolerance"; components outside [min_size, max_size] are dropped (not split).
 * ========================================================================================== */

typedef struct duet_clustering_settings {
  float tolerance_m; /* max neighbour distance in a cluster [m], > 0 (default 0.10) */
  uint32_t min_size; /* smaller clusters are dropped [points] (default 1) */
  uint32_t max_size; /* larger clusters are dropped [points] (default UINT32_MAX) */
} duet_clustering_settings;

DUET_API void duet_clustering_settings_init(duet_clustering_settings* settings);

/* Label of a point that belongs to no kept cluster. */
#define DUET_UNCLUSTERED UINT32_MAX

/* Clusters `count` points (xyz, read in place). labels[i] (count uint32 at labels_stride)
 * receives the cluster of point i: clusters are numbered 0, 1, ... by decreasing size (ties:
 * smallest point index first); DUET_UNCLUSTERED for non-finite points and dropped clusters.
 * *cluster_count (if not NULL) receives the number of clusters (0 on error).
 * Thread-safe: buffers are the caller's; errors go to `device`. */
DUET_API void duet_euclidean_clusters(duet_device device, const float* xyz, size_t xyz_stride,
                                      size_t count, const duet_clustering_settings* settings,
                                      uint32_t* labels, size_t labels_stride,
                                      size_t* cluster_count);

/* ============================================================================================
 * Segmentation (paper §2.2, Fig. 4) of a cloud with normals in a frame with +z up:
 *  1. points outside [floor + min_height_m, floor + max_height_m] are ignored;
 *  2. a point whose normal deviates from vertical by more than max_floor_tilt_deg is an
 *     obstacle;
 *  3. the other points are clustered; a cluster whose centre is higher than
 *     floor_height_threshold_m above the floor is an obstacle, otherwise floor; clusters
 *     smaller than clustering.min_size are ignored. Points with a NaN normal are ignored.
 * ========================================================================================== */

enum duet_point_label {
  DUET_LABEL_FLOOR = 0,    /* traversable floor: clears grid cells */
  DUET_LABEL_OBSTACLE = 1, /* marks grid cells occupied */
  DUET_LABEL_IGNORED = 2   /* outside the height band, no normal, or speckle */
};

typedef struct duet_segmentation_settings {
  float floor_z_m;                /* floor height [m] (default 0) */
  float max_floor_tilt_deg;       /* [deg] (default 20) */
  float floor_height_threshold_m; /* [m] (default 0.10) */
  float min_height_m;             /* [m] above the floor (default -0.30) */
  float max_height_m;             /* [m] above the floor (default 1.20) */
  duet_clustering_settings clustering; /* default {0.10, 20, UINT32_MAX} */
} duet_segmentation_settings;

DUET_API void duet_segmentation_settings_init(duet_segmentation_settings* settings);

/* Labels `count` points (xyz and normals, count x 3 floats each, read in place; normals are
 * copied once when normals_stride != 12). labels (count uint8 at labels_stride) receives
 * enum duet_point_label values. Thread-safe: buffers are the caller's; errors go to `device`. */
DUET_API void duet_segment(duet_device device, const float* xyz, size_t xyz_stride,
                           const float* normals, size_t normals_stride, size_t count,
                           const duet_segmentation_settings* settings, uint8_t* labels,
                           size_t labels_stride);

/* ============================================================================================
 * Occupancy grid: 2D log-odds grid in the x-y plane of the map frame. Cell (ix, iy) covers
 * [origin_x + ix*res, origin_x + (ix+1)*res) x [origin_y + iy*res, ...); storage row-major,
 * row 0 at the lowest y. Never-observed cells hold NaN log-odds ("unknown"). The grid starts
 * empty (0 x 0) and grows (never shrinks) to contain the data of each update.
 * ========================================================================================== */

/* Creates an empty grid of cells `resolution_m` [m] wide (finite, > 0). Ownership: the caller
 * owns the returned reference; the grid keeps a reference to `device`. Thread-safe. */
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
 * DUET_ERROR_INVALID_ARGUMENT); ignored and non-finite points are skipped. Growing beyond
 * 2^28 cells -> DUET_ERROR_OUT_OF_RANGE. Errors found before the update starts (handles,
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

#ifdef __cplusplus
} /* extern "C" */
#endif

#endif /* DUET_H */
