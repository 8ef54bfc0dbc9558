/*
 * duet.h - the C API of duet (libduet.so), version 1.
 *
 * Modelled on Embree's C API (rtcore_device.h): opaque reference-counted handles created by a
 * device, errors reported through the device instead of return codes, caller buffers passed
 * as (pointer, byte stride, count).
 *
 * Headers: include duet.h only; it includes the others, which hold the rest of the API.
 *   duet.h          these conventions, the version, handles and errors, the device
 *   duet_cloud.h    clouds, back-projection, voxel filter, normals, clustering, segmentation
 *   duet_grid.h     the occupancy grid
 *   duet_planner.h  the exploration planner (status codes, results, calls), scan-to-map matching
 *   duet_runtime.h  the robot loop;  duet_sim.h  the simulator;  duet_version.h  DUET_VERSION
 *
 * ---------------------------------------------------------------------------------------------
 * Handles
 *   duet_device  owns the TBB task arena (every kernel runs inside it) and the error state.
 *   duet_cloud   a point cloud (positions, optional colours, normals, curvature) owned by duet.
 *   duet_grid    a 2D log-odds occupancy grid owned by duet.
 *   duet_planner the exploration and control kernels' state: a copy of a grid, its observation
 *                model and inflation, sensors, goal blacklist, dynamic window state (see
 *                "Exploration planner"). Holds a reference to its device like clouds and grids.
 *   duet_runtime the whole robot loop: frames and odometry in, commands, pose and maps out
 *                (duet_runtime.h).
 *   duet_sim     the simulator: a world and a robot stepped with commands (duet_sim.h).
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
 *   The error goes to the device the bad handle belongs to when duet knows it and it lives (a
 *   handle of another type; one of the last 65536 released handles), else to the calling
 *   thread's no-device slot (see Errors).
 *   A released handle is detected without reading freed memory and is never recycled, so a
 *   stale handle can never silently refer to a newer object.
 *
 * Errors
 *   No function returns an error code. Each device keeps the FIRST error that happened since
 *   the last duet_device_get_error() (get-and-clear) with its message, and an
 *   optional callback that is called synchronously for every error. Errors that have no usable
 *   device (NULL or released device handle, a failed duet_device_new, a NULL handle, a dead
 *   handle whose device cannot be known or is released) go to a thread-local "no device" slot read with
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
 * Frames and units
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
 * duet functions, including on the same device. An error of a call made inside a callback is
 * recorded as usual but calls no callback (no recursion). */
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

/* Message of the error duet_device_get_error() returns - the first since the previous
 * get_error - or, after that call, of the error it returned ("" if there was none). Later
 * errors before the next get_error do not replace it (each reaches the callback). NULL: this
 * thread's no-device slot. The returned string is owned by duet and valid until the next
 * duet_device_get_error_message() call on the same thread. Thread-safe. */
DUET_API const char* duet_device_get_error_message(duet_device device);

/* Sets (callback != NULL) or removes (callback == NULL) the error callback of `device`.
 * device == NULL sets the process-wide callback of the no-device slot.
 * `user_ptr` is passed back unchanged; the caller keeps ownership. Thread-safe. */
DUET_API void duet_device_set_error_callback(duet_device device, duet_error_callback callback,
                                             void* user_ptr);

#ifdef __cplusplus
} /* extern "C" */
#endif

/* The rest of the API: clouds, the occupancy grid, the exploration planner. */
#include "duet_cloud.h"
#include "duet_grid.h"
#include "duet_planner.h"

/* The robot loop (duet_runtime.h) and the simulator (duet_sim.h). */
#include "duet_runtime.h"
#include "duet_sim.h"

#endif /* DUET_H */
