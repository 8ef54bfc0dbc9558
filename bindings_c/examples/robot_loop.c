/*
 * robot_loop.c - a complete robot program on duet's C API alone (C99): the simulator stands in
 * for the robot's drivers, the runtime explores.
 *
 *   every control period (50 ms):
 *     simulator: drive one period with the last command -> rendered RGB-D frames + odometry
 *     runtime:   push the frames and the odometry, spin one period -> the next command
 *   until the explorer is done or the time limit; then score the map against the world, print
 *   the result and (optionally) save the maps.
 *
 * On a real robot the simulator's part is your drivers' callbacks (duet_runtime_push_rgbd and
 * duet_runtime_push_odometry from their threads) and your motor loop reads
 * duet_runtime_get_command; duet_runtime_start runs the control period on duet's own thread.
 *
 * Usage: robot_loop [WORLD [SEED [MAX_TIME_S [OUT_DIR]]]]   (default: lab 1 900, no output)
 * With the same world and seed, the trajectory is the one `duet explore -w WORLD -s SEED`
 * gives (both run the same lockstep runtime on the same simulator).
 * Exit status 0 when the run worked (no API error), whatever the coverage.
 */
#include <duet.h>

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#define MAX_SENSORS 8
#define ODOM_BATCH 64

static void on_error(void* user_ptr, enum duet_error code, const char* message) {
  (void)user_ptr;
  fprintf(stderr, "robot_loop: %s: %s\n", duet_error_string(code), message);
}

static void on_event(void* user_ptr, double time_s, const char* message) {
  int quiet = *(const int*)user_ptr;
  if (!quiet) fprintf(stderr, "[%7.2f s] %s\n", time_s, message);
}

static int failed(duet_device device, const char* what) {
  enum duet_error e = duet_device_get_error(device);
  if (e == DUET_ERROR_NONE) return 0;
  fprintf(stderr, "robot_loop: %s failed (%s)\n", what, duet_error_string(e));
  return 1;
}

int main(int argc, char** argv) {
  const char* world = argc > 1 ? argv[1] : "lab";
  const uint64_t seed = argc > 2 ? (uint64_t)strtoull(argv[2], NULL, 10) : 1u;
  const double max_time = argc > 3 ? atof(argv[3]) : 900.0;
  const char* out_dir = argc > 4 ? argv[4] : NULL;
  const int quiet = getenv("ROBOT_LOOP_QUIET") != NULL;
  /* Render only the frames the mapper takes (1 Hz), as `duet explore` does by default. */
  const char* sets[] = {"runtime.sensor_rate_hz=1"};
  int status = 1;

  duet_device device = duet_device_new(getenv("ROBOT_LOOP_DEVICE"));
  if (device == NULL) {
    fprintf(stderr, "robot_loop: duet_device_new: %s\n", duet_device_get_error_message(NULL));
    return 1;
  }
  duet_device_set_error_callback(device, on_error, NULL);
  duet_sim sim = duet_sim_new(device, world, DUET_PROFILE_NAME_OR_FILE, "dual", sets, 1, seed);
  duet_runtime rt = duet_runtime_new(device, DUET_PROFILE_NAME_OR_FILE, "dual", sets, 1, seed);
  if (failed(device, "creating the simulator and the runtime")) goto done;
  duet_runtime_set_time_origin(rt, 0.0); /* the simulator's clock starts at 0 */
  duet_runtime_set_event_callback(rt, on_event, (void*)&quiet);

  size_t n_sensors = duet_runtime_get_sensor_count(rt);
  if (n_sensors > MAX_SENSORS || n_sensors != duet_sim_get_sensor_count(sim)) {
    fprintf(stderr, "robot_loop: unexpected sensor count %zu\n", n_sensors);
    goto done;
  }
  duet_runtime_sensor_info info[MAX_SENSORS];
  uint16_t* depth[MAX_SENSORS] = {0};
  uint8_t* rgb[MAX_SENSORS] = {0};
  for (size_t i = 0; i < n_sensors; ++i) {
    duet_runtime_get_sensor_info(rt, i, &info[i]);
    depth[i] = (uint16_t*)malloc(sizeof(uint16_t) * (size_t)info[i].width * (size_t)info[i].height);
    rgb[i] = (uint8_t*)malloc(3u * (size_t)info[i].width * (size_t)info[i].height);
    if (depth[i] == NULL || rgb[i] == NULL) goto free_buffers;
  }

  {
    const double dt = duet_runtime_get_control_period(rt);
    double t = 0.0;
    duet_twist command = {0.0f, 0.0f};
    duet_runtime_status st;
    double stamps[ODOM_BATCH];
    duet_pose2 poses[ODOM_BATCH];
    duet_twist twists[ODOM_BATCH];
    for (;;) {
      /* The robot moves one period with the last command; its sensors and wheels report. */
      duet_sim_step(sim, command, dt);
      t = t + dt;
      size_t n;
      while ((n = duet_sim_take_odometry(sim, stamps, poses, twists, ODOM_BATCH)) > 0)
        for (size_t k = 0; k < n; ++k) duet_runtime_push_odometry(rt, stamps[k], poses[k], twists[k]);
      for (size_t i = 0; i < n_sensors; ++i) {
        double stamp;
        while (duet_sim_take_frame(sim, i, &stamp, depth[i], 0, rgb[i], 0, info[i].width, info[i].height)) {
          duet_rgbd_image image;
          duet_rgbd_image_init(&image);
          image.stamp_s = stamp;
          image.depth = depth[i];
          image.width = info[i].width;
          image.height = info[i].height;
          image.depth_format = DUET_DEPTH_U16;
          image.depth_units_per_m = info[i].depth_units_per_m;
          image.color = rgb[i];
          duet_runtime_push_rgbd(rt, i, &image);
        }
      }
      /* One control period of the robot's runtime, then its command for the next. */
      duet_runtime_spin_once(rt, t);
      command = duet_runtime_get_command(rt);
      if (failed(device, "the control loop")) goto free_buffers;
      duet_runtime_get_status(rt, &st);
      if (st.state == DUET_EXPLORER_DONE || t + 1e-9 >= max_time) break;
    }

    duet_grid grid = duet_runtime_get_grid(rt);
    double coverage = 0.0, explored = 0.0;
    duet_sim_score(sim, grid, &coverage, &explored);
    duet_grid_release(grid);
    char detail[256];
    duet_runtime_get_stop_detail(rt, detail, sizeof detail);
    duet_runtime_stats stats;
    duet_runtime_get_stats(rt, &stats);
    printf("time_s: %.2f\n", t);
    printf("state: %s\n", duet_explorer_state_string(st.state));
    printf("stop_detail: %s\n", detail);
    printf("coverage: %.4f\n", coverage);
    printf("explored_m2: %.2f\n", explored);
    printf("collisions: %zu\n", duet_sim_get_collisions(sim));
    printf("map_updates: %llu\n", (unsigned long long)stats.sets_integrated);
    printf("pose_health: %s\n", duet_pose_health_string(st.health));
    if (out_dir != NULL) {
      duet_runtime_save(rt, out_dir);
      if (failed(device, "saving the maps")) goto free_buffers;
      printf("saved: %s\n", out_dir);
    }
    if (!failed(device, "scoring")) status = 0;
  }

free_buffers:
  for (size_t i = 0; i < MAX_SENSORS; ++i) {
    free(depth[i]);
    free(rgb[i]);
  }
done:
  duet_runtime_release(rt);
  duet_sim_release(sim);
  duet_device_release(device);
  return status;
}
