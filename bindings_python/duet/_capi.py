"""ctypes declarations of libduet.so's C API (duet.h, duet_cloud.h, duet_grid.h, duet_planner.h,
duet_runtime.h, duet_sim.h).

The structures mirror the C headers field by field (C layout, native alignment); the
prototypes give every function its argument and return types, so a wrong call is a Python
TypeError instead of undefined behaviour.
"""
import ctypes
import ctypes.util
import os
from ctypes import (POINTER, Structure, c_char, c_char_p, c_double, c_float, c_int, c_int8, c_size_t,
                    c_uint8, c_uint16, c_uint64, c_void_p)

# ---- structures ------------------------------------------------------------------------------


class Pose2(Structure):
    _fields_ = [("x", c_float), ("y", c_float), ("theta", c_float)]


class Twist(Structure):
    _fields_ = [("v", c_float), ("omega", c_float)]


class RgbdImage(Structure):  # duet_rgbd_image
    _fields_ = [("stamp_s", c_double), ("depth", c_void_p), ("width", c_int), ("height", c_int),
                ("depth_row_stride", c_size_t), ("depth_format", c_int), ("depth_units_per_m", c_float),
                ("color", c_void_p), ("color_row_stride", c_size_t), ("color_channels", c_int),
                ("color_bgr", c_int), ("intrinsics", POINTER(c_float))]


class SensorInfo(Structure):  # duet_runtime_sensor_info
    _fields_ = [("width", c_int), ("height", c_int), ("fx", c_float), ("fy", c_float), ("cx", c_float),
                ("cy", c_float), ("depth_units_per_m", c_float), ("rate_hz", c_float),
                ("T_robot_optical", c_float * 16), ("name", c_char * 64)]


class RuntimeStatus(Structure):  # duet_runtime_status
    _fields_ = [("time_s", c_double), ("command", Twist), ("pose", Pose2), ("map_from_odom", Pose2),
                ("health", c_int), ("state", c_int), ("paused", c_int), ("has_goal", c_int), ("goal", Pose2),
                ("path_points", c_size_t), ("map_updates", c_size_t),
                ("visual_odometry", c_int), ("odometry_health", c_int)]


_STATS_FIELDS = ["frames_pushed", "frames_queue_overflow", "frames_paused", "odometry_pushed",
                 "odometry_queue_overflow", "odometry_paused", "frames_invalid", "frames_out_of_order",
                 "frames_garbled", "frames_dropped_sync", "odometry_invalid", "odometry_out_of_order",
                 "odometry_jumps", "clock_restarts", "sensor_silences", "sets_integrated", "blind_periods",
                 "relocalizations", "loop_closures", "control_periods", "frames_recorded",
                 "frames_record_dropped", "gyro_pushed", "gyro_invalid", "gyro_gaps"]


class RuntimeStats(Structure):  # duet_runtime_stats
    _fields_ = [(name, c_uint64) for name in _STATS_FIELDS]


EVENT_FN = ctypes.CFUNCTYPE(None, c_void_p, c_double, c_char_p)

# enums
DEPTH_U16, DEPTH_F32 = 0, 1
PROFILE_NAME_OR_FILE, PROFILE_YAML_TEXT = 0, 1
EXPLORER_STATES = ["idle", "exploring", "returning_home", "patrolling", "done"]
POSE_HEALTH = ["good", "degraded", "lost"]
ERRORS = ["NONE", "INVALID_ARGUMENT", "INVALID_OPERATION", "OUT_OF_RANGE", "IO", "PARSE", "UNSUPPORTED",
          "OUT_OF_MEMORY", "UNKNOWN"]

# ---- the library -----------------------------------------------------------------------------


def _candidates():
    env = os.environ.get("DUET_LIBRARY")
    if env:
        yield env
    here = os.path.dirname(os.path.abspath(__file__))
    # Installed: <prefix>/lib/python3/dist-packages/duet -> <prefix>/lib/libduet.so.0
    for up in (os.path.join(here, "..", "..", ".."), os.path.join(here, "..", "..", "..", "..", "lib")):
        yield os.path.normpath(os.path.join(up, "libduet.so.0"))
    found = ctypes.util.find_library("duet")
    if found:
        yield found
    yield "libduet.so.0"


def _load():
    errors = []
    for path in _candidates():
        if os.path.sep in path and not os.path.exists(path):
            continue
        try:
            return ctypes.CDLL(path)
        except OSError as e:  # keep looking, and say where we looked
            errors.append(f"{path}: {e}")
    raise ImportError("duet: libduet.so not found (set DUET_LIBRARY to its path); tried:\n  " + "\n  ".join(errors))


lib = _load()

H = c_void_p  # every handle is an opaque pointer


def _proto(name, restype, *argtypes):
    f = getattr(lib, name)
    f.restype = restype
    f.argtypes = list(argtypes)


_proto("duet_get_version", c_int)
_proto("duet_get_version_string", c_char_p)
_proto("duet_error_string", c_char_p, c_int)
_proto("duet_device_new", H, c_char_p)
_proto("duet_device_release", None, H)
_proto("duet_device_get_error", c_int, H)
_proto("duet_device_get_error_message", c_char_p, H)
_proto("duet_device_get_thread_count", c_int, H)
# clouds and grids
_proto("duet_cloud_release", None, H)
_proto("duet_cloud_get_size", c_size_t, H)
_proto("duet_cloud_has_colors", c_int, H)
_proto("duet_cloud_copy_points", None, H, POINTER(c_float), c_size_t, c_size_t)
_proto("duet_cloud_copy_colors", None, H, POINTER(c_uint8), c_size_t, c_size_t)
_proto("duet_grid_release", None, H)
_proto("duet_grid_get_width", c_int, H)
_proto("duet_grid_get_height", c_int, H)
_proto("duet_grid_get_resolution", c_float, H)
_proto("duet_grid_get_origin", None, H, POINTER(c_float), POINTER(c_float))
_proto("duet_grid_get_known_cells", c_size_t, H)
_proto("duet_grid_copy_logodds", None, H, POINTER(c_float), c_size_t)
_proto("duet_grid_copy_probabilities", None, H, POINTER(c_float), c_size_t)
_proto("duet_grid_copy_ros", None, H, POINTER(c_int8), c_size_t, c_float, c_float)
_proto("duet_grid_load_map_server", H, H, c_char_p)
_proto("duet_grid_save_map_server", None, H, c_char_p)
# runtime
_proto("duet_runtime_new", H, H, c_int, c_char_p, POINTER(c_char_p), c_size_t, c_uint64)
_proto("duet_runtime_release", None, H)
_proto("duet_runtime_get_sensor_count", c_size_t, H)
_proto("duet_runtime_get_sensor_info", None, H, c_size_t, POINTER(SensorInfo))
_proto("duet_runtime_get_control_period", c_double, H)
_proto("duet_runtime_set_time_origin", None, H, c_double)
_proto("duet_rgbd_image_init", None, POINTER(RgbdImage))
_proto("duet_runtime_push_rgbd", None, H, c_size_t, POINTER(RgbdImage))
_proto("duet_runtime_push_odometry", None, H, c_double, Pose2, Twist)
_proto("duet_runtime_push_gyro", None, H, c_double, c_float)
_proto("duet_runtime_spin_once", None, H, c_double)
_proto("duet_time_now", c_double)
_proto("duet_runtime_start", None, H, c_void_p, c_void_p)
_proto("duet_runtime_pause", None, H)
_proto("duet_runtime_resume", None, H)
_proto("duet_runtime_stop", None, H)
_proto("duet_runtime_return_home", None, H)
_proto("duet_runtime_join", None, H)
_proto("duet_runtime_save", None, H, c_char_p)
_proto("duet_runtime_record", None, H, c_char_p)
_proto("duet_runtime_get_status", None, H, POINTER(RuntimeStatus))
_proto("duet_runtime_get_command", Twist, H)
_proto("duet_runtime_get_stop_detail", c_size_t, H, c_char_p, c_size_t)
_proto("duet_runtime_get_path", c_size_t, H, POINTER(c_float), c_size_t, c_size_t)
_proto("duet_runtime_get_grid", H, H)
_proto("duet_runtime_get_cloud", H, H)
_proto("duet_runtime_get_stats", None, H, POINTER(RuntimeStats))
_proto("duet_runtime_set_event_callback", None, H, EVENT_FN, c_void_p)
# simulator
_proto("duet_sim_new", H, H, c_char_p, c_int, c_char_p, POINTER(c_char_p), c_size_t, c_uint64)
_proto("duet_sim_release", None, H)
_proto("duet_sim_get_time", c_double, H)
_proto("duet_sim_step", None, H, Twist, c_double)
_proto("duet_sim_get_sensor_count", c_size_t, H)
_proto("duet_sim_get_sensor_info", None, H, c_size_t, POINTER(SensorInfo))
_proto("duet_sim_get_frames_waiting", c_size_t, H, c_size_t)
_proto("duet_sim_take_frame", c_int, H, c_size_t, POINTER(c_double), POINTER(c_uint16), c_size_t, POINTER(c_uint8),
       c_size_t, c_int, c_int)
_proto("duet_sim_take_odometry", c_size_t, H, POINTER(c_double), POINTER(Pose2), POINTER(Twist), c_size_t)
_proto("duet_sim_get_true_pose", Pose2, H)
_proto("duet_sim_get_collisions", c_size_t, H)
_proto("duet_sim_score", None, H, H, POINTER(c_double), POINTER(c_double))
