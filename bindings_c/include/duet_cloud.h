/*
 * duet_cloud.h - point clouds in the C API of duet: the cloud handle, back-projection of depth
 * images, voxel filter, normals, Euclidean clustering and segmentation.
 * Part of duet.h: include duet.h, not this file directly. The conventions at the top of
 * duet.h (handles, errors, buffers, settings, thread safety, frames) hold here.
 */
#include "duet.h" /* before the guard: alone, this file then declares all of duet.h in order */
#ifndef DUET_CLOUD_H
#define DUET_CLOUD_H

#ifdef __cplusplus
extern "C" {
#endif

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
  const void* depth;                  /* width * height pixels of depth_format; uint16 in the
                                       * machine's native byte order */
  int width, height;                  /* [px], > 0: must be set (init leaves 0) */
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

/* Fills `frame` with defaults: no data, size 0 x 0 (set width and height: a forgotten size is
 * an error, never an over-read), DUET_DEPTH_U16 at 1000 units/m, no colour,
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

#ifdef __cplusplus
} /* extern "C" */
#endif

#endif /* DUET_CLOUD_H */
