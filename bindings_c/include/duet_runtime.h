/*
 * duet_runtime.h - the whole robot loop through the C API: push your RGB-D frames and wheel
 * odometry in, take velocity commands, the pose, the explorer's state and the maps out.
 * Included by duet.h; the conventions of duet.h (handles, errors, buffers, frames, units)
 * hold here too.
 *
 * A duet_runtime is made on a device from a robot profile (the YAML `duet profile` prints;
 * the sensors' intrinsics and mounts, the chassis, every setting of the pipeline). It runs the
 * same ExplorationRuntime `duet explore` and `duet run` run: synchronizer -> mapper (1 Hz) ->
 * scan-to-map correction and loop closure -> Procedure 1 / frontier goals -> dynamic window.
 *
 * Two ways to run it:
 *   - duet_runtime_spin_once(rt, now): one control period on the caller's thread (single-
 *     threaded embedding, simulators, replays). With the profile's runtime.execution
 *     (lockstep by default) the same inputs give the same commands, bit for bit.
 *   - duet_runtime_start(rt, clock, user): the runtime runs its own control thread at the
 *     profile's control rate (20 Hz), paced by the wall clock, with background execution (the
 *     map update and the decisions never make the control period wait).
 *   The first of the two fixes the mode; the other is then DUET_ERROR_INVALID_OPERATION.
 *
 * Time
 *   Stamps and times are seconds on ONE clock of yours (a driver's stamps, ROS time, a
 *   simulator's time) - the same for every push and every spin. The runtime works on a time
 *   line near 0: it subtracts a time origin, set by duet_runtime_set_time_origin() or, if
 *   never set, from the first stamp or time it is given, rounded down to a whole second, minus
 *   10 s (so frames stamped a little before the first message still count). Times it returns
 *   are on your clock again.
 *
 * Bad input is counted, not fatal: stamps that are NaN/inf, out of order or duplicated,
 * odometry jumps no chassis makes, frames of all-noise depth, silent sensors - the runtime
 * drops or repairs them and counts them (duet_runtime_stats; the event callback says what it
 * did). Bad ARGUMENTS (NULL pointers, a sensor index out of range, a frame of the wrong size)
 * are errors on the device as everywhere in duet.h.
 *
 * Thread safety: every function may be called from any thread. Pushes are wait-free for the
 * control loop (a short lock on a bounded queue; a full queue drops its oldest entry, counted).
 * Getters of the status, the command and the grid read what the last control period published
 * and never wait for the control loop. duet_runtime_get_cloud() and duet_runtime_save() need the
 * mapper itself: they wait for the running map update (at most one, ~0.1-0.5 s) and hold the
 * control loop meanwhile - call them at the end of a run or at a low rate.
 */
#ifndef DUET_RUNTIME_H
#define DUET_RUNTIME_H

#include "duet.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct duet_runtime_t* duet_runtime;

/* How duet_runtime_new reads `profile`. */
enum duet_profile_kind {
  DUET_PROFILE_NAME_OR_FILE = 0, /* a built-in name ("dual", "single") or a path to a YAML file */
  DUET_PROFILE_YAML_TEXT = 1     /* the profile's YAML text itself */
};

/* Makes a runtime on `device` from a profile, with `set_count` overrides "KEY=VALUE" laid over
 * it in order (as `duet explore --set`, e.g. "runtime.sensor_rate_hz=1",
 * "exploration.on_done=return_home"; NULL with set_count 0 for none). `seed` seeds Procedure 1's
 * random simulation as `duet explore --seed` does (the same seed gives the same decisions);
 * 0 keeps the profile's exploration.strategy.simulation.seed. Errors: NULL device or profile
 * (INVALID_ARGUMENT), a profile file that cannot be read (IO), malformed YAML or an unknown
 * key (PARSE), a value out of range (INVALID_ARGUMENT) - the message names the file, line and
 * key. Returns NULL on error. The runtime holds a reference to its device. Thread-safe. */
DUET_API duet_runtime duet_runtime_new(duet_device device, enum duet_profile_kind kind, const char* profile,
                                       const char* const* sets, size_t set_count, uint64_t seed);
DUET_API void duet_runtime_retain(duet_runtime runtime);
/* Dropping the last reference stops the runtime's thread (if started): it waits for the
 * thread's current period, then frees everything (a recording is closed). From the runtime's
 * own event callback it cannot wait for itself: the thread then ends and frees the runtime after
 * the callback returns. */
DUET_API void duet_runtime_release(duet_runtime runtime);

/* ---- profiles ----------------------------------------------------------------------------- */

/* Every kernel setting of a robot profile, for the kernel and planner calls of duet.h: what the
 * runtime would run with. The duet_*_settings_init() functions give the built-in "dual"
 * profile's values (the one place duet's defaults come from). */
typedef struct duet_profile_settings {
  float grid_resolution_m;                          /* mapping.grid_resolution_m [m] */
  duet_back_projection_settings back_projection;
  duet_voxel_filter_settings voxel_filter;
  duet_normal_settings normals;
  duet_segmentation_settings segmentation;
  duet_grid_update_settings grid_update;
  duet_scan_match_settings scan_match;              /* the runtime's scan-to-map correction */
  duet_observation_settings observation;
  duet_inflation_settings inflation;
  duet_path_settings path;
  duet_exploration_settings exploration;            /* Procedure 1 + frontier + eps_R */
  duet_dwa_settings dwa;
  size_t sensor_count;                              /* the profile's sensors, <= 16 */
  duet_sensor_sector sensors[16];                   /* their fans (extrinsics, field of view, range, rays) */
} duet_profile_settings;

/* Loads a profile (as duet_runtime_new: kind, profile, set_count overrides) into *out. Errors
 * name the file, line and key (IO, PARSE, INVALID_ARGUMENT); *out is then unchanged.
 * Thread-safe. */
DUET_API void duet_profile_settings_load(duet_device device, enum duet_profile_kind kind, const char* profile,
                                         const char* const* sets, size_t set_count, duet_profile_settings* out);

/* What the runtime expects of sensor i (from the profile). */
typedef struct duet_runtime_sensor_info {
  int width, height;          /* [px]: every frame pushed for this sensor has this size */
  float fx, fy, cx, cy;       /* pinhole intrinsics [px] */
  float depth_units_per_m;    /* the profile's depth units (uint16 frames may use others) */
  float rate_hz;              /* the frame rate the runtime expects (runtime.sensor_rate_hz) */
  float T_robot_optical[16];  /* the sensor's mount: optical frame -> robot frame, column-major */
  char name[64];              /* the profile's name of the sensor, NUL-terminated (truncated to 63 bytes;
                               * the ROS node's topic namespace) */
} duet_runtime_sensor_info;

/* Number of RGB-D sensors of the profile (0 on error). Thread-safe. */
DUET_API size_t duet_runtime_get_sensor_count(duet_runtime runtime);
/* Sensor `sensor`'s geometry into *out. INVALID_ARGUMENT for NULL out or an index out of
 * range. Thread-safe. */
DUET_API void duet_runtime_get_sensor_info(duet_runtime runtime, size_t sensor, duet_runtime_sensor_info* out);
/* The control period [s] (1 / runtime.control_rate_hz). 0 on error. Thread-safe. */
DUET_API double duet_runtime_get_control_period(duet_runtime runtime);

/* Sets the time origin (see "Time" above) to `origin_s` on your clock, e.g. 0 for a
 * simulator whose clock starts at 0. Only before the first push or spin (else
 * INVALID_OPERATION); finite. Thread-safe. */
DUET_API void duet_runtime_set_time_origin(duet_runtime runtime, double origin_s);

/* ---- input ------------------------------------------------------------------------------- */

/* One RGB-D frame of one sensor, read during the push call and copied (the caller may reuse
 * its buffers when the call returns). */
typedef struct duet_rgbd_image {
  double stamp_s;                      /* capture time on your clock [s] */
  const void* depth;                   /* width * height pixels, row-major (required) */
  int width, height;                   /* [px], must equal the sensor's (duet_runtime_sensor_info) */
  size_t depth_row_stride;             /* bytes between rows, 0 = packed */
  enum duet_depth_format depth_format; /* DUET_DEPTH_U16 (native byte order) or DUET_DEPTH_F32 metres */
  float depth_units_per_m;             /* DUET_DEPTH_U16: raw units per metre, > 0 (1000 = mm) */
  const uint8_t* color;                /* registered colour, same size; NULL = none */
  size_t color_row_stride;             /* bytes between rows, 0 = packed */
  int color_channels;                  /* 3 or 4 */
  int color_bgr;                       /* 1 = B,G,R order (OpenCV), 0 = R,G,B */
  const float* intrinsics;             /* NULL = the sensor's (profile); else this frame's fx, fy, cx, cy
                                        * [px] (fx, fy > 0; cx in [0, width], cy in [0, height]), used to
                                        * back-project this frame (the planner's fans stay the profile's;
                                        * recordings keep the profile's) */
} duet_rgbd_image;

/* Fills *image with: stamp NaN, no buffers, size 0 x 0 (set all three: a forgotten size is an
 * error, never an over-read), DUET_DEPTH_U16 at 1000 units/m, 3 channels RGB, the sensor's
 * intrinsics (NULL). Thread-safe. */
DUET_API void duet_rgbd_image_init(duet_rgbd_image* image);

/* Queues a frame of sensor `sensor` (0-based, the profile's order). Depth in other units than
 * the profile's is converted; float depth that is NaN, inf or <= 0 means no return. Errors
 * (INVALID_ARGUMENT): NULL image or depth, a size other than the sensor's, a bad stride,
 * channels or units. A non-finite, out-of-order or duplicate stamp is not an error: the
 * runtime drops and counts the frame. While paused, frames are dropped and counted. Any
 * thread, concurrently with everything. */
DUET_API void duet_runtime_push_rgbd(duet_runtime runtime, size_t sensor, const duet_rgbd_image* image);

/* Queues a wheel odometry message: the pose in the odometry frame [m, rad] and the measured
 * twist [m/s, rad/s] at stamp_s on your clock. Non-finite or out-of-order values are counted
 * drops; a pose jump no chassis makes is absorbed (counted). Any thread. */
DUET_API void duet_runtime_push_odometry(duet_runtime runtime, double stamp_s, duet_pose2 pose, duet_twist twist);

/* Queues a gyro sample: the yaw rate [rad/s, counter-clockwise] measured up to stamp_s (your
 * clock). From the first sample on, the odometry the runtime takes gets its heading from the
 * gyro and its distance from the wheels (what a Kobuki's firmware does; it keeps the heading
 * when the wheels slip): each wheel message's heading change is the gyro's integral since the
 * previous message (a sample's rate holds back to the sample before; a gyro lagging the wheels by
 * up to 50 ms has its last rate held). A step the gyro does not cover keeps the wheels' change
 * (counted: gyro_gaps). Non-finite values and stamps not after the previous sample are counted
 * drops (gyro_invalid). Push the gyro at least as fast as the odometry. Any thread. */
DUET_API void duet_runtime_push_gyro(duet_runtime runtime, double stamp_s, float yaw_rate_rps);

/* ---- running ----------------------------------------------------------------------------- */

/* One control period at `now_s` on your clock (non-decreasing; a time before the last is
 * INVALID_ARGUMENT): the queued frames and odometry -> synchronizer -> map update when due ->
 * control. The command is then duet_runtime_get_command(). On the caller's thread; calls on one
 * runtime are serialised. INVALID_OPERATION once duet_runtime_start() was called. A spin while
 * paused does nothing. */
DUET_API void duet_runtime_spin_once(duet_runtime runtime, double now_s);

/* Your clock for duet_runtime_start: seconds, non-decreasing. Called on the runtime's thread. */
typedef double (*duet_clock_fn)(void* user_ptr);

/* Seconds on the monotonic clock (CLOCK_MONOTONIC), the default of duet_runtime_start. */
DUET_API double duet_time_now(void);

/* Starts the runtime's own control thread: every control period (wall clock) it takes the
 * queued input and ticks at clock(user_ptr) (NULL clock: duet_time_now()). Execution is
 * background: map updates and decisions run on the device's other threads. INVALID_OPERATION
 * if already started or if duet_runtime_spin_once() was used. Thread-safe. */
DUET_API void duet_runtime_start(duet_runtime runtime, duet_clock_fn clock, void* user_ptr);

/* Pause: the robot holds still (command 0) and the runtime's time stands still - no mapping, no
 * planning, goal time limits do not run out; frames and odometry pushed meanwhile are dropped
 * (counted). Resume: on from where it paused. Both idempotent. Thread-safe. */
DUET_API void duet_runtime_pause(duet_runtime runtime);
DUET_API void duet_runtime_resume(duet_runtime runtime);

/* Stop exploring now: the explorer is done ("stopped by the operator"), the command is 0; the
 * runtime keeps mapping while it is spun or its thread runs. Thread-safe. */
DUET_API void duet_runtime_stop(duet_runtime runtime);

/* Stop exploring and drive back to where the run started (through the usual goals and
 * paths); the explorer is done when home or when no path home is found. Thread-safe. */
DUET_API void duet_runtime_return_home(duet_runtime runtime);

/* Ends the runtime's own thread (if started) and waits for it and for the map update in
 * flight. The runtime can still be read and saved. Thread-safe; idempotent. */
DUET_API void duet_runtime_join(duet_runtime runtime);

/* Writes into folder `dir` (created if needed) the files `duet explore` writes for the
 * robot's side of a run: grid.yaml + grid.pgm (map_server), grid.png, cloud.pcd (binary
 * compressed), trajectory.tum (the pose estimate at every control period) and summary.json
 * (state, stop reason, counters, timing). Each file is written under a temporary name and
 * renamed. IO error naming the path if it cannot be written. Waits for the map update in
 * flight (see the top of this file). Thread-safe. */
DUET_API void duet_runtime_save(duet_runtime runtime, const char* dir);

/* Records every input stream the runtime takes - each sensor's frames (16-bit PNG depth, PNG
 * colour), the odometry, the profile as run - into folder `dir` (new or empty), in duet's
 * recording format (docs/recording.md: TUM RGB-D's rgb.txt/depth.txt per sensor, odometry.txt,
 * with each message's arrival time). `duet replay DIR` maps it again; a lockstep run replays to
 * the same grid and cloud, bit for bit. Only before the first control period (else
 * INVALID_OPERATION); IO error naming the folder if it is not empty or not writable. A writer
 * thread writes the files; when it falls behind, frames are dropped and counted
 * (frames_record_dropped) - control never waits for the disk. The recording is closed by
 * duet_runtime_join() or the last release. Thread-safe. */
DUET_API void duet_runtime_record(duet_runtime runtime, const char* dir);

/* ---- output ------------------------------------------------------------------------------ */

enum duet_explorer_state {
  DUET_EXPLORER_IDLE = 0,           /* no map yet */
  DUET_EXPLORER_EXPLORING = 1,
  DUET_EXPLORER_RETURNING_HOME = 2,
  DUET_EXPLORER_PATROLLING = 3,
  DUET_EXPLORER_DONE = 4            /* see stop_detail */
};

/* How far to trust the pose estimate. */
enum duet_pose_health {
  DUET_POSE_GOOD = 0,      /* scan matches against the map are being accepted */
  DUET_POSE_DEGRADED = 1,  /* the last 3 scan matches failed, or the robot was relocalised in the
                            * last 10 s, or the scan-to-map correction is off (odometry only) */
  DUET_POSE_LOST = 2       /* no frame mapped for several periods: the robot holds still */
};

typedef struct duet_runtime_status {
  double time_s;                 /* the time of the last control period, your clock (NaN before the first) */
  duet_twist command;            /* the command of that period (0 while paused or done) */
  duet_pose2 pose;               /* pose estimate in the map frame */
  duet_pose2 map_from_odom;      /* the correction: map <- odometry frame (ROS: the map -> odom tf) */
  enum duet_pose_health health;
  enum duet_explorer_state state;
  int paused;                    /* 1 while paused */
  int has_goal;                  /* 1: goal is valid */
  duet_pose2 goal;               /* the current goal (map frame) */
  size_t path_points;            /* points of the current path (duet_runtime_get_path) */
  size_t map_updates;            /* map updates so far */
  int visual_odometry;           /* 1: localization.visual_odometry is on (vision fused with the wheels by an EKF) */
  enum duet_pose_health odometry_health;  /* vision's health when on: GOOD - tracked within degraded_after_s;
                                           * DEGRADED - vision fails or is weak, the wheels carry the pose;
                                           * LOST - no visual update for lost_after_s. Off: DEGRADED (wheels only) */
} duet_runtime_status;

/* The status of the last control period into *out. Never waits for the control loop. */
DUET_API void duet_runtime_get_status(duet_runtime runtime, duet_runtime_status* out);

/* The latest command (v [m/s], omega [rad/s]; zero before the first period, while paused, when
 * done). Never waits for the control loop; any thread (a motor driver's own loop). */
DUET_API duet_twist duet_runtime_get_command(duet_runtime runtime);

/* Why the explorer stopped, in words ("explored: no frontier left", "stopped by the operator";
 * "" while exploring), copied NUL-terminated into buf (truncated to capacity - 1). Returns the
 * full length (without the NUL), so a call with capacity 0 (buf may be NULL) sizes the buffer. */
DUET_API size_t duet_runtime_get_stop_detail(duet_runtime runtime, char* buf, size_t capacity);

/* The current path (map frame, from the robot to the goal) as x, y pairs: copies
 * min(count, capacity) points to xy (2 floats per point at xy_stride bytes, 0 = packed) and
 * returns the path's point count (0 without a goal). capacity 0: xy may be NULL. */
DUET_API size_t duet_runtime_get_path(duet_runtime runtime, float* xy, size_t xy_stride, size_t capacity);

/* A copy of the latest map's occupancy grid as a new grid handle on the runtime's device (read
 * it with duet_grid_copy_ros / _probabilities / _logodds, duet_grid_get_origin; release it).
 * An empty grid (0 x 0) before the first map update. Never waits for the control loop. */
DUET_API duet_grid duet_runtime_get_grid(duet_runtime runtime);

/* A copy of the 3D map (map frame, coloured, voxel-filtered) as a new cloud handle. Waits for
 * the map update in flight (see the top of this file). */
DUET_API duet_cloud duet_runtime_get_cloud(duet_runtime runtime);

typedef struct duet_runtime_stats {
  uint64_t frames_pushed, frames_queue_overflow, frames_paused;   /* at the push side */
  uint64_t odometry_pushed, odometry_queue_overflow, odometry_paused;
  uint64_t frames_invalid;        /* non-finite stamp: dropped */
  uint64_t frames_out_of_order;   /* stamp not after the sensor's previous frame (incl. duplicates): dropped */
  uint64_t frames_garbled;        /* depth that is noise: mapped as missing */
  uint64_t frames_dropped_sync;   /* frames the synchronizer could not pair (all sensors) */
  uint64_t odometry_invalid;      /* non-finite stamp, pose or twist: dropped */
  uint64_t odometry_out_of_order; /* stamp not after the previous one (incl. duplicates): dropped */
  uint64_t odometry_jumps;        /* steps no chassis makes: absorbed */
  uint64_t clock_restarts;        /* your clock stepped back: the synchronizer restarted */
  uint64_t sensor_silences;       /* a sensor went silent while another delivered */
  uint64_t sets_integrated;       /* synchronized frame sets mapped */
  uint64_t blind_periods;         /* control periods held still with no frame mapped */
  uint64_t relocalizations;       /* wide re-matches that moved the pose */
  uint64_t loop_closures;         /* closures that moved the map frame */
  uint64_t control_periods;       /* ticks run */
  uint64_t frames_recorded;       /* duet_runtime_record(): frames written */
  uint64_t frames_record_dropped; /* ... dropped (the disk was slower than the sensors) */
  uint64_t gyro_pushed;           /* gyro samples pushed */
  uint64_t gyro_invalid;          /* ... dropped: non-finite, or a stamp not after the previous */
  uint64_t gyro_gaps;             /* odometry steps the gyro did not cover: the wheels' heading kept */
} duet_runtime_stats;

DUET_API void duet_runtime_get_stats(duet_runtime runtime, duet_runtime_stats* out);

/* What the runtime noticed and did (a sensor went silent, the clock stepped back, a relocalisation,
 * the explorer's state changed, ...), one line each. Called on the thread that runs the control
 * period (duet_runtime_spin_once's caller or the runtime's thread), after the period, never
 * while a lock of the runtime is held: it may call any duet function. It must return quickly.
 * `message` is valid during the call only. NULL removes the callback. Thread-safe. */
typedef void (*duet_runtime_event_fn)(void* user_ptr, double time_s, const char* message);
DUET_API void duet_runtime_set_event_callback(duet_runtime runtime, duet_runtime_event_fn callback, void* user_ptr);

/* Static names: "exploring", "good", ... ("?" for values out of range). */
DUET_API const char* duet_explorer_state_string(enum duet_explorer_state state);
DUET_API const char* duet_pose_health_string(enum duet_pose_health health);

#ifdef __cplusplus
}
#endif

#endif /* DUET_RUNTIME_H */
