/*
 * duet_sim.h - duet's simulator through the C API: a differential-drive robot with the
 * profile's RGB-D sensors in a world (Embree ray casting, the same simulator `duet explore`
 * runs), stepped with your velocity commands, giving rendered frames and wheel odometry - so an
 * integration can be tested the way it will run on the robot (bindings_c/examples/robot_loop.c:
 * simulator -> duet_runtime -> simulator). Included by duet.h; its conventions hold here.
 *
 * Time: the simulator's clock starts at 0 s and moves only with duet_sim_step(). Frames are
 * rendered at the profile's runtime.sensor_rate_hz from the robot's TRUE pose (the first at
 * t = 0), with the Kinect's depth noise; odometry comes at the chassis' odometry rate (50 Hz)
 * with wheel noise and a gyro heading. The same world, profile and seed give the same frames
 * and odometry for the same commands, bit for bit.
 *
 * Thread safety: calls on one simulator are serialised internally; distinct simulators run in
 * parallel.
 */
#ifndef DUET_SIM_H
#define DUET_SIM_H

#include "duet.h"
#include "duet_runtime.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct duet_sim_t* duet_sim;

/* Makes a simulator on `device`: `world` is a built-in world name ("lab"), a world YAML file
 * or a map_server map YAML (walls from the image, the start pose from a `.start` file beside
 * it or the free cell nearest the map's centre); the robot comes from the profile (as in
 * duet_runtime_new: kind, profile, set_count overrides "KEY=VALUE"); `seed` seeds the wheel
 * and depth noise (as `duet explore --seed`). Errors name the file, line and key. Returns NULL
 * on error. Thread-safe. */
DUET_API duet_sim duet_sim_new(duet_device device, const char* world, enum duet_profile_kind kind, const char* profile,
                               const char* const* sets, size_t set_count, uint64_t seed);
DUET_API void duet_sim_retain(duet_sim sim);
DUET_API void duet_sim_release(duet_sim sim);

/* The simulator's time [s] (0 at creation). NaN on error. */
DUET_API double duet_sim_get_time(duet_sim sim);

/* Drives with `command` (held over the whole step; the chassis applies its acceleration and
 * speed limits) for dt_s seconds, (0, 10]: physics at 5 ms, odometry at its rate, frames when
 * due. INVALID_ARGUMENT for a non-finite command or a dt out of range. */
DUET_API void duet_sim_step(duet_sim sim, duet_twist command, double dt_s);

/* Sensor i's image geometry (the profile's; the same as duet_runtime_get_sensor_info). */
DUET_API size_t duet_sim_get_sensor_count(duet_sim sim);
DUET_API void duet_sim_get_sensor_info(duet_sim sim, size_t sensor, duet_runtime_sensor_info* out);

/* Frames of sensor `sensor` rendered and not yet taken (at most 64 are kept; older ones are
 * dropped). */
DUET_API size_t duet_sim_get_frames_waiting(duet_sim sim, size_t sensor);

/* Takes the oldest waiting frame of `sensor`: its stamp into *stamp_s, its depth (uint16 in
 * the sensor's depth_units_per_m, 0 = no return, native byte order) into `depth` (width *
 * height pixels at depth_row_stride bytes per row, 0 = packed), its colour (R, G, B) into
 * `rgb` (rgb_row_stride, 0 = packed; NULL = not wanted). width and height must be the
 * sensor's (INVALID_ARGUMENT otherwise: no over-read, no over-write). Returns 1 if a frame
 * was taken, 0 if none was waiting (the buffers are then untouched). */
DUET_API int duet_sim_take_frame(duet_sim sim, size_t sensor, double* stamp_s, uint16_t* depth, size_t depth_row_stride,
                                 uint8_t* rgb, size_t rgb_row_stride, int width, int height);

/* Takes up to `capacity` of the oldest waiting odometry messages: stamps [s], poses in the
 * odometry frame (starts at the world's start pose) and measured twists; any of the three
 * arrays may be NULL if not wanted. Returns the number taken; the rest stay waiting. */
DUET_API size_t duet_sim_take_odometry(duet_sim sim, double* stamps_s, duet_pose2* poses, duet_twist* twists, size_t capacity);

/* The ground truth: the robot's true pose (world frame) and the contacts with walls so far. */
DUET_API duet_pose2 duet_sim_get_true_pose(duet_sim sim);
DUET_API size_t duet_sim_get_collisions(duet_sim sim);

/* Scores a map of this world as `duet explore` does: the share of the world's reachable free
 * area (from the start, for the profile's robot radius) that `grid` knows (free or occupied)
 * into *coverage ([0, 1]), and the area the grid knows [m^2] into *explored_m2 (either may be
 * NULL). The grid's frame is the world frame (a runtime's map frame when the odometry started
 * at the world's start pose, as the simulator's does). */
DUET_API void duet_sim_score(duet_sim sim, duet_grid grid, double* coverage, double* explored_m2);

#ifdef __cplusplus
}
#endif

#endif /* DUET_SIM_H */
