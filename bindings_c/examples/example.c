/*
 * example.c - the duet C API end to end, in C99.
 *
 * A robot with two Kinect-like sensors at the paper's Eq. (6) extrinsics stands at the origin
 * of a room: floor at z = 0, a wall 2 m ahead (x = 2) and a wall 1.5 m to its right
 * (y = -1.5). The program renders both depth images (uint16 millimetres) analytically,
 * back-projects them into one cloud in the robot frame, voxel-filters it, estimates normals,
 * segments floor / obstacles, integrates a 2D occupancy grid, and prints what it found.
 * Then it plans like the robot would (paper §3, Fig. 6): an exploration planner takes a copy
 * of the grid, decides where to go next (partial map simulation, else frontier search), plans
 * a global path there and computes the first dynamic-window command.
 * Every call is checked; the program returns 0 only if everything worked, the map looks like
 * the room and the planner found a goal, a path to it and a command.
 */
#include <duet.h>

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#define WIDTH 640
#define HEIGHT 480
#define PI_F 3.14159265358979f

static const float kFrontWallX = 2.0f;  /* wall ahead [m] */
static const float kRightWallY = -1.5f; /* wall on the right [m] */
static const float kMaxRange = 5.0f;    /* no return beyond [m] */

/* Error callback: print every error as it happens (the program still checks each call). */
static void on_error(void* user_ptr, enum duet_error code, const char* message) {
  const char* who = (const char*)user_ptr;
  fprintf(stderr, "[%s] %s: %s\n", who, duet_error_string(code), message);
}

/* Returns 1 (and prints) if the device recorded an error since the last check. */
static int failed(duet_device device, const char* what) {
  enum duet_error e = duet_device_get_error(device);
  if (e != DUET_ERROR_NONE) {
    fprintf(stderr, "example: %s failed: %s (%s)\n", what, duet_error_string(e),
            duet_device_get_error_message(device));
    return 1;
  }
  return 0;
}

/* Renders the depth image a camera at pose T_robot_camera (column-major) sees in the room. */
static void render_depth(const duet_sensor_frame* f, const float* T, uint16_t* depth_mm) {
  const float ox = T[12], oy = T[13], oz = T[14];
  int u, v;
  for (v = 0; v < f->height; ++v) {
    for (u = 0; u < f->width; ++u) {
      /* ray with optical z = 1, so the ray parameter t is the depth */
      const float c[3] = {((float)u - f->cx) / f->fx, ((float)v - f->cy) / f->fy, 1.0f};
      const float dx = T[0] * c[0] + T[4] * c[1] + T[8] * c[2];
      const float dy = T[1] * c[0] + T[5] * c[1] + T[9] * c[2];
      const float dz = T[2] * c[0] + T[6] * c[1] + T[10] * c[2];
      float t = INFINITY;
      if (dz < 0.0f && -oz / dz < t) t = -oz / dz;                           /* floor */
      if (dx > 0.0f && (kFrontWallX - ox) / dx < t) t = (kFrontWallX - ox) / dx; /* front wall */
      if (dy < 0.0f && (kRightWallY - oy) / dy < t) t = (kRightWallY - oy) / dy; /* right wall */
      depth_mm[(size_t)v * (size_t)f->width + (size_t)u] =
          (t > 0.0f && t <= kMaxRange) ? (uint16_t)(t * 1000.0f + 0.5f) : 0;
    }
  }
}

int main(void) {
  int status = 1;
  duet_device device = NULL;
  duet_cloud raw = NULL, filtered = NULL;
  duet_grid grid = NULL;
  duet_planner planner = NULL;
  duet_decision decision;
  duet_path_result path;
  duet_dwa_result command;
  float* waypoints = NULL;
  const duet_pose2 robot = {0.0f, 0.0f, 0.0f}; /* the robot's pose in the map (= robot) frame */
  const duet_twist standing = {0.0f, 0.0f};
  uint16_t* depth[2] = {NULL, NULL};
  uint8_t* labels = NULL;
  float* cells = NULL;
  duet_sensor_frame frames[2];
  duet_back_projection_settings bp;
  duet_voxel_filter_settings vf;
  duet_normal_settings ns;
  duet_segmentation_settings seg;
  duet_grid_update_settings gu;
  size_t offsets[3];
  const float* points = NULL;
  const float* normals = NULL;
  size_t points_stride = 0, normals_stride = 0, n_raw, n_filtered, n_cells, i;
  size_t n_label[3] = {0, 0, 0}, occupied = 0, free_cells = 0, unknown = 0;
  int s, width, height;
  float origin_x = 0.0f, origin_y = 0.0f;

  printf("duet %s (header %s)\n", duet_get_version_string(), DUET_VERSION_STRING);
  if (duet_get_version() != DUET_VERSION) {
    fprintf(stderr, "example: library version %d != header version %d\n", duet_get_version(),
            DUET_VERSION);
    return 1;
  }

  device = duet_device_new("threads=2,verbose=0");
  if (device == NULL) {
    fprintf(stderr, "example: duet_device_new failed: %s\n", duet_device_get_error_message(NULL));
    return 1;
  }
  duet_device_set_error_callback(device, on_error, (void*)"duet");

  /* ---- two sensors, Eq. (6): x y z [m], ZYX Euler yaw pitch roll [rad] ---- */
  for (s = 0; s < 2; ++s) {
    duet_sensor_frame_init(&frames[s]); /* Kinect intrinsics, uint16 mm; the size is ours to set */
    depth[s] = (uint16_t*)malloc(sizeof(uint16_t) * WIDTH * HEIGHT);
    if (depth[s] == NULL) {
      fprintf(stderr, "example: out of memory\n");
      goto done;
    }
    frames[s].depth = depth[s];
    frames[s].width = WIDTH;
    frames[s].height = HEIGHT;
    frames[s].depth_format = DUET_DEPTH_U16;
    frames[s].depth_units_per_m = 1000.0f;
  }
  duet_camera_mount_matrix(-0.118f, 0.0f, 0.271f, 0.0f, 0.0f, 0.0f, frames[0].T_robot_camera);
  duet_camera_mount_matrix(-0.118f, 0.0f, 0.481f, -PI_F / 2.0f, 0.0f, 0.0f,
                           frames[1].T_robot_camera);
  for (s = 0; s < 2; ++s) render_depth(&frames[s], frames[s].T_robot_camera, depth[s]);

  /* ---- back-projection into one cloud in the robot frame ---- */
  raw = duet_cloud_new(device);
  filtered = duet_cloud_new(device);
  grid = duet_grid_new(device, 0.05f);
  if (failed(device, "creating the cloud and grid")) goto done;

  duet_back_projection_settings_init(&bp);
  duet_back_project(raw, frames, 2, &bp, offsets);
  if (failed(device, "duet_back_project")) goto done;
  n_raw = duet_cloud_get_size(raw);
  printf("back-projected points: %zu (sensor 1: %zu, sensor 2: %zu)\n", n_raw,
         offsets[1] - offsets[0], offsets[2] - offsets[1]);

  /* ---- voxel filter (0.05 m), reading the raw cloud's storage in place ---- */
  duet_cloud_get_points(raw, &points, &points_stride);
  duet_voxel_filter_settings_init(&vf);
  vf.leaf_size_m = 0.05f;
  duet_voxel_filter(filtered, points, points_stride, NULL, 0, n_raw, &vf);
  if (failed(device, "duet_voxel_filter")) goto done;
  n_filtered = duet_cloud_get_size(filtered);
  printf("voxel-filtered points: %zu\n", n_filtered);

  /* ---- normals (k = 10), facing the sensors ---- */
  duet_normal_settings_init(&ns);
  ns.k = 10;
  ns.viewpoint[0] = -0.118f;
  ns.viewpoint[1] = 0.0f;
  ns.viewpoint[2] = 0.376f;
  duet_cloud_estimate_normals(filtered, &ns);
  if (failed(device, "duet_cloud_estimate_normals")) goto done;

  /* ---- segmentation: floor / obstacle / ignored ---- */
  duet_cloud_get_points(filtered, &points, &points_stride);
  duet_cloud_get_normals(filtered, &normals, &normals_stride);
  if (failed(device, "borrowing the filtered cloud")) goto done;
  labels = (uint8_t*)malloc(n_filtered > 0 ? n_filtered : 1);
  if (labels == NULL) {
    fprintf(stderr, "example: out of memory\n");
    goto done;
  }
  duet_segmentation_settings_init(&seg);
  seg.floor_z_m = 0.0f;
  duet_segment(device, points, points_stride, normals, normals_stride, n_filtered, &seg, labels, 1);
  if (failed(device, "duet_segment")) goto done;
  for (i = 0; i < n_filtered; ++i) {
    if (labels[i] > DUET_LABEL_IGNORED) {
      fprintf(stderr, "example: bad label %u\n", (unsigned)labels[i]);
      goto done;
    }
    ++n_label[labels[i]];
  }
  printf("labels: floor %zu, obstacle %zu, ignored %zu\n", n_label[DUET_LABEL_FLOOR],
         n_label[DUET_LABEL_OBSTACLE], n_label[DUET_LABEL_IGNORED]);

  /* ---- occupancy grid from both sensors (both at x = -0.118, y = 0 in the robot frame) ---- */
  duet_grid_update_settings_init(&gu);
  duet_grid_update(grid, -0.118f, 0.0f, points, points_stride, labels, 1, n_filtered, &gu);
  if (failed(device, "duet_grid_update")) goto done;
  width = duet_grid_get_width(grid);
  height = duet_grid_get_height(grid);
  duet_grid_get_origin(grid, &origin_x, &origin_y);
  if (failed(device, "reading the grid")) goto done;
  n_cells = (size_t)width * (size_t)height;
  cells = (float*)malloc(sizeof(float) * (n_cells > 0 ? n_cells : 1));
  if (cells == NULL) {
    fprintf(stderr, "example: out of memory\n");
    goto done;
  }
  /* One scan moves a cell to p = 0.70 (hit) or p = 0.40 (miss); -1 = never observed. */
  duet_grid_copy_probabilities(grid, cells, n_cells);
  if (failed(device, "duet_grid_copy_probabilities")) goto done;
  for (i = 0; i < n_cells; ++i) {
    if (cells[i] < 0.0f) {
      ++unknown;
    } else if (cells[i] > 0.5f) {
      ++occupied;
    } else if (cells[i] < 0.5f) {
      ++free_cells;
    }
  }
  printf("grid: %d x %d cells of %.2f m, origin (%.2f, %.2f)\n", width, height,
         (double)duet_grid_get_resolution(grid), (double)origin_x, (double)origin_y);
  printf("cells: occupied %zu, free %zu, unknown %zu (p > 0.5, p < 0.5, never seen)\n", occupied,
         free_cells, unknown);

  /* ---- sanity of the result: the room must show up ---- */
  if (n_raw == 0 || offsets[1] == offsets[0] || offsets[2] == offsets[1] || n_filtered == 0 ||
      n_filtered >= n_raw || n_label[DUET_LABEL_FLOOR] == 0 || n_label[DUET_LABEL_OBSTACLE] == 0 ||
      occupied == 0 || free_cells == 0) {
    fprintf(stderr, "example: the map does not look like the room\n");
    goto done;
  }

  /* ---- exploration planner (Fig. 6) on a copy of the grid, then the global path and the
   * first dynamic-window command ---- */
  planner = duet_planner_new(device); /* default sensors: the paper's two Kinects, 30 rays each */
  duet_planner_set_grid_from(planner, grid, NULL, NULL); /* default thresholds, radius 0.20 m */
  if (failed(device, "duet_planner_set_grid_from")) goto done;
  duet_planner_decide(planner, robot, 0.0, NULL, &decision);
  if (failed(device, "duet_planner_decide")) goto done;
  printf("decision: %s, goal (%.2f, %.2f, %.2f), reward %.2f bits\n",
         duet_exploration_status_string(decision.status), (double)decision.goal.x,
         (double)decision.goal.y, (double)decision.goal.theta, (double)decision.reward_bits);
  if (decision.status != DUET_EXPLORATION_SIMULATED_GOAL &&
      decision.status != DUET_EXPLORATION_FRONTIER_GOAL) {
    fprintf(stderr, "example: the planner found no goal in a half-explored room\n");
    goto done;
  }
  /* Path: ask for the count first (capacity 0), then fetch the waypoints. */
  duet_planner_plan_path(planner, robot.x, robot.y, decision.goal.x, decision.goal.y, NULL, &path,
                         NULL, 0);
  if (failed(device, "duet_planner_plan_path")) goto done;
  if (path.status != DUET_PATH_FOUND || path.waypoint_count == 0) {
    fprintf(stderr, "example: no path to the goal (%s)\n", duet_path_status_string(path.status));
    goto done;
  }
  waypoints = (float*)malloc(2 * sizeof(float) * path.waypoint_count);
  if (waypoints == NULL) {
    fprintf(stderr, "example: out of memory\n");
    goto done;
  }
  duet_planner_plan_path(planner, robot.x, robot.y, decision.goal.x, decision.goal.y, NULL, &path,
                         waypoints, path.waypoint_count);
  if (failed(device, "duet_planner_plan_path")) goto done;
  printf("path: %zu waypoints, %.2f m\n", path.waypoint_count, (double)path.length_m);
  duet_planner_dwa_step(planner, robot, standing, waypoints, 0, path.waypoint_count, NULL, &command);
  if (failed(device, "duet_planner_dwa_step")) goto done;
  printf("command: %s, v %.3f m/s, omega %.3f rad/s\n", duet_dwa_status_string(command.status),
         (double)command.cmd.v, (double)command.cmd.omega);
  if (command.status != DUET_DWA_OK && command.status != DUET_DWA_ROTATE_IN_PLACE &&
      command.status != DUET_DWA_GOAL_REACHED) {
    fprintf(stderr, "example: no command toward the goal\n");
    goto done;
  }

  printf("ok\n");
  status = 0;

done:
  free(waypoints);
  if (planner != NULL) duet_planner_release(planner);
  free(cells);
  free(labels);
  free(depth[0]);
  free(depth[1]);
  if (grid != NULL) duet_grid_release(grid);
  if (filtered != NULL) duet_cloud_release(filtered);
  if (raw != NULL) duet_cloud_release(raw);
  duet_device_release(device);
  if (duet_device_get_error(NULL) != DUET_ERROR_NONE) {
    fprintf(stderr, "example: releasing failed: %s\n", duet_device_get_error_message(NULL));
    status = 1;
  }
  return status;
}
