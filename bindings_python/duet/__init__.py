"""duet from Python: the C API of libduet.so through ctypes, with numpy arrays for images, grids
and clouds, and exceptions carrying the C error message.

    import duet
    dev = duet.Device()
    sim = duet.Sim(dev, "lab", sets=["runtime.sensor_rate_hz=1"], seed=1)
    rt = duet.Runtime(dev, "dual", sets=["runtime.sensor_rate_hz=1"], seed=1)
    rt.set_time_origin(0.0)
    t, cmd = 0.0, (0.0, 0.0)
    while t < 60.0:
        sim.step(cmd, rt.control_period)
        t += rt.control_period
        for stamp, pose, twist in sim.take_odometry():
            rt.push_odometry(stamp, pose, twist)
        for i in range(rt.sensor_count):
            while (frame := sim.take_frame(i)) is not None:
                rt.push_rgbd(i, *frame)
        rt.spin_once(t)
        cmd = rt.command()

Every object keeps its device alive; release() (or the garbage collector, or a `with` block)
frees it. Errors: DuetError(code, message), code one of duet.ERRORS ("INVALID_ARGUMENT", ...).
Units, frames and thread safety are those of duet.h / duet_cloud.h / duet_grid.h / duet_planner.h /
duet_runtime.h / duet_sim.h.
"""
import ctypes

import numpy as np

from . import _capi as _c
from ._capi import ERRORS, EXPLORER_STATES, POSE_HEALTH

__all__ = ["Device", "Runtime", "Sim", "Grid", "Cloud", "DuetError", "version", "ERRORS", "EXPLORER_STATES",
           "POSE_HEALTH"]


def version():
    """The loaded library's version, "MAJOR.MINOR.PATCH"."""
    return _c.lib.duet_get_version_string().decode()


class DuetError(RuntimeError):
    """An error the C API reported: .code (a name of duet.ERRORS) and the library's message."""

    def __init__(self, code, message):
        self.code = ERRORS[code] if 0 <= code < len(ERRORS) else str(code)
        super().__init__(f"{self.code}: {message}")


def _raise_pending(device_handle):
    code = _c.lib.duet_device_get_error(device_handle)
    if code != 0:
        msg = _c.lib.duet_device_get_error_message(device_handle)
        raise DuetError(code, msg.decode(errors="replace") if msg else "")
    code = _c.lib.duet_device_get_error(None)  # errors no device could take (NULL handles)
    if code != 0:
        msg = _c.lib.duet_device_get_error_message(None)
        raise DuetError(code, msg.decode(errors="replace") if msg else "")


def _sets(sets):
    sets = [s.encode() for s in (sets or [])]
    arr = (ctypes.c_char_p * max(len(sets), 1))(*sets)
    return arr, len(sets)


def _profile(profile):
    """(kind, bytes): YAML text if it has a newline or a ':', else a built-in name or a file."""
    text = profile if isinstance(profile, str) else str(profile)
    kind = _c.PROFILE_YAML_TEXT if ("\n" in text or ": " in text) else _c.PROFILE_NAME_OR_FILE
    return kind, text.encode()


class _Handle:
    _release = None

    def __init__(self, handle, device):
        self._h = handle
        self._device = device  # keeps the device (and its error slot) alive

    @property
    def handle(self):
        if not self._h:
            raise DuetError(2, f"{type(self).__name__} was released")
        return self._h

    def _check(self):
        _raise_pending(self._device.handle)

    def release(self):
        if self._h:
            type(self)._release(self._h)
            self._h = None

    def __del__(self):
        try:
            self.release()
        except Exception:  # interpreter shutdown: nothing left to report to
            pass

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.release()


class Device(_Handle):
    """Creates everything and owns the thread pool. config: "threads=N" (0 = all cores)."""

    _release = staticmethod(_c.lib.duet_device_release)

    def __init__(self, config="threads=0"):
        h = _c.lib.duet_device_new(config.encode() if config is not None else None)
        if not h:
            _raise_pending(None)
            raise DuetError(8, "duet_device_new failed")
        super().__init__(h, self)

    @property
    def threads(self):
        return _c.lib.duet_device_get_thread_count(self.handle)

    def _check(self):
        _raise_pending(self.handle)


class Grid(_Handle):
    """A 2D log-odds occupancy grid (map frame: row 0 at the lowest y; NaN = unknown)."""

    _release = staticmethod(_c.lib.duet_grid_release)

    @classmethod
    def load_map_server(cls, device, yaml_path):
        h = _c.lib.duet_grid_load_map_server(device.handle, str(yaml_path).encode())
        _raise_pending(device.handle)
        return cls(h, device)

    def save_map_server(self, yaml_path):
        _c.lib.duet_grid_save_map_server(self.handle, str(yaml_path).encode())
        self._check()

    @property
    def shape(self):
        """(height, width) in cells."""
        return _c.lib.duet_grid_get_height(self.handle), _c.lib.duet_grid_get_width(self.handle)

    @property
    def resolution(self):
        return _c.lib.duet_grid_get_resolution(self.handle)

    @property
    def origin(self):
        """World (x, y) of the lower-left corner of cell (0, 0) [m]."""
        x, y = ctypes.c_float(), ctypes.c_float()
        _c.lib.duet_grid_get_origin(self.handle, ctypes.byref(x), ctypes.byref(y))
        return x.value, y.value

    @property
    def known_cells(self):
        return _c.lib.duet_grid_get_known_cells(self.handle)

    def logodds(self):
        out = np.empty(self.shape, dtype=np.float32)
        _c.lib.duet_grid_copy_logodds(self.handle, out.ctypes.data_as(ctypes.POINTER(ctypes.c_float)), out.size)
        self._check()
        return out

    def probabilities(self):
        out = np.empty(self.shape, dtype=np.float32)
        _c.lib.duet_grid_copy_probabilities(self.handle, out.ctypes.data_as(ctypes.POINTER(ctypes.c_float)), out.size)
        self._check()
        return out

    def ros(self, occupied=0.65, free=0.45):
        """ROS OccupancyGrid data: 100 occupied, 0 free, -1 unknown (int8, (height, width))."""
        out = np.empty(self.shape, dtype=np.int8)
        _c.lib.duet_grid_copy_ros(self.handle, out.ctypes.data_as(ctypes.POINTER(ctypes.c_int8)), out.size, occupied, free)
        self._check()
        return out


class Cloud(_Handle):
    """A point cloud (map frame)."""

    _release = staticmethod(_c.lib.duet_cloud_release)

    def __len__(self):
        return _c.lib.duet_cloud_get_size(self.handle)

    def points(self):
        """(N, 3) float32 x, y, z [m]."""
        out = np.empty((len(self), 3), dtype=np.float32)
        _c.lib.duet_cloud_copy_points(self.handle, out.ctypes.data_as(ctypes.POINTER(ctypes.c_float)), 0, out.shape[0])
        self._check()
        return out

    def colors(self):
        """(N, 3) uint8 R, G, B (None if the cloud has no colour)."""
        if not _c.lib.duet_cloud_has_colors(self.handle):
            return None
        out = np.empty((len(self), 3), dtype=np.uint8)
        _c.lib.duet_cloud_copy_colors(self.handle, out.ctypes.data_as(ctypes.POINTER(ctypes.c_uint8)), 0, out.shape[0])
        self._check()
        return out


def _sensor_info(si):
    return {"width": si.width, "height": si.height, "fx": si.fx, "fy": si.fy, "cx": si.cx, "cy": si.cy,
            "depth_units_per_m": si.depth_units_per_m, "rate_hz": si.rate_hz,
            "T_robot_optical": np.array(list(si.T_robot_optical), dtype=np.float32).reshape(4, 4).T,
            "name": si.name.decode("utf-8", "replace")}


class Runtime(_Handle):
    """The robot loop (duet_runtime.h): push frames and odometry, spin (or start its thread),
    read the command, the pose, the state and the maps."""

    _release = staticmethod(_c.lib.duet_runtime_release)

    def __init__(self, device, profile="dual", sets=None, seed=1):
        kind, text = _profile(profile)
        arr, n = _sets(sets)
        h = _c.lib.duet_runtime_new(device.handle, kind, text, arr, n, seed)
        _raise_pending(device.handle)
        super().__init__(h, device)
        self._callback = None  # the ctypes callback must outlive its registration

    # -- geometry
    @property
    def sensor_count(self):
        return _c.lib.duet_runtime_get_sensor_count(self.handle)

    def sensor_info(self, sensor):
        si = _c.SensorInfo()
        _c.lib.duet_runtime_get_sensor_info(self.handle, sensor, ctypes.byref(si))
        self._check()
        return _sensor_info(si)

    @property
    def control_period(self):
        return _c.lib.duet_runtime_get_control_period(self.handle)

    def set_time_origin(self, origin_s):
        _c.lib.duet_runtime_set_time_origin(self.handle, origin_s)
        self._check()

    # -- input
    def push_rgbd(self, sensor, stamp_s, depth, rgb=None, depth_units_per_m=None, intrinsics=None):
        """depth: (H, W) uint16 (in depth_units_per_m, default the sensor's) or float32 metres;
        rgb: (H, W, 3) or (H, W, 4) uint8 R, G, B(, A), or None; intrinsics: this frame's
        (fx, fy, cx, cy) or None for the sensor's. Copied by the call."""
        depth = np.asarray(depth)
        if depth.ndim != 2 or depth.dtype not in (np.uint16, np.float32):
            raise ValueError(f"depth must be a 2D uint16 or float32 array, got {depth.dtype} {depth.shape}")
        depth = np.ascontiguousarray(depth)
        im = _c.RgbdImage()
        _c.lib.duet_rgbd_image_init(ctypes.byref(im))
        im.stamp_s = stamp_s
        im.depth = depth.ctypes.data
        im.height, im.width = depth.shape
        im.depth_row_stride = depth.strides[0]
        im.depth_format = _c.DEPTH_U16 if depth.dtype == np.uint16 else _c.DEPTH_F32
        if depth.dtype == np.uint16:
            im.depth_units_per_m = depth_units_per_m if depth_units_per_m else self.sensor_info(sensor)["depth_units_per_m"]
        if rgb is not None:
            rgb = np.ascontiguousarray(np.asarray(rgb, dtype=np.uint8))
            if rgb.ndim != 3 or rgb.shape[:2] != depth.shape or rgb.shape[2] not in (3, 4):
                raise ValueError(f"rgb must be (H, W, 3 or 4) uint8 of the depth's size, got {rgb.shape}")
            im.color = rgb.ctypes.data
            im.color_row_stride = rgb.strides[0]
            im.color_channels = rgb.shape[2]
        if intrinsics is not None:
            k = (ctypes.c_float * 4)(*[float(v) for v in intrinsics])
            im.intrinsics = ctypes.cast(k, ctypes.POINTER(ctypes.c_float))
        _c.lib.duet_runtime_push_rgbd(self.handle, sensor, ctypes.byref(im))
        self._check()

    def push_odometry(self, stamp_s, pose, twist):
        """pose: (x, y, theta) in the odometry frame [m, rad]; twist: (v, omega) [m/s, rad/s]."""
        _c.lib.duet_runtime_push_odometry(self.handle, stamp_s, _c.Pose2(*pose), _c.Twist(*twist))
        self._check()

    def push_gyro(self, stamp_s, yaw_rate_rps):
        """A gyro sample: from the first on, the odometry's heading comes from the gyro."""
        _c.lib.duet_runtime_push_gyro(self.handle, stamp_s, yaw_rate_rps)
        self._check()

    # -- running
    def spin_once(self, now_s):
        _c.lib.duet_runtime_spin_once(self.handle, now_s)
        self._check()

    def start(self):
        """Runs the control loop on the runtime's own thread (monotonic clock: duet.time_now())."""
        _c.lib.duet_runtime_start(self.handle, None, None)
        self._check()

    def pause(self):
        _c.lib.duet_runtime_pause(self.handle)
        self._check()

    def resume(self):
        _c.lib.duet_runtime_resume(self.handle)
        self._check()

    def stop(self):
        _c.lib.duet_runtime_stop(self.handle)
        self._check()

    def return_home(self):
        _c.lib.duet_runtime_return_home(self.handle)
        self._check()

    def join(self):
        _c.lib.duet_runtime_join(self.handle)
        self._check()

    def save(self, folder):
        _c.lib.duet_runtime_save(self.handle, str(folder).encode())
        self._check()

    def record(self, folder):
        _c.lib.duet_runtime_record(self.handle, str(folder).encode())
        self._check()

    def set_event_callback(self, fn):
        """fn(time_s, message) on the control thread after each period; None removes it."""
        self._callback = _c.EVENT_FN(lambda _u, t, m: fn(t, m.decode(errors="replace"))) if fn else _c.EVENT_FN()
        _c.lib.duet_runtime_set_event_callback(self.handle, self._callback, None)
        self._check()

    # -- output
    def command(self):
        """(v [m/s], omega [rad/s]) of the last control period."""
        t = _c.lib.duet_runtime_get_command(self.handle)
        self._check()
        return t.v, t.omega

    def status(self):
        s = _c.RuntimeStatus()
        _c.lib.duet_runtime_get_status(self.handle, ctypes.byref(s))
        self._check()
        return {"time_s": s.time_s, "command": (s.command.v, s.command.omega),
                "pose": (s.pose.x, s.pose.y, s.pose.theta),
                "map_from_odom": (s.map_from_odom.x, s.map_from_odom.y, s.map_from_odom.theta),
                "health": POSE_HEALTH[s.health], "state": EXPLORER_STATES[s.state], "paused": bool(s.paused),
                "goal": (s.goal.x, s.goal.y, s.goal.theta) if s.has_goal else None,
                "path_points": s.path_points, "map_updates": s.map_updates,
                "visual_odometry": bool(s.visual_odometry), "odometry_health": POSE_HEALTH[s.odometry_health]}

    def stop_detail(self):
        n = _c.lib.duet_runtime_get_stop_detail(self.handle, None, 0)
        buf = ctypes.create_string_buffer(n + 1)
        _c.lib.duet_runtime_get_stop_detail(self.handle, buf, n + 1)
        self._check()
        return buf.value.decode(errors="replace")

    def path(self):
        """(N, 2) float32 x, y of the current path (map frame)."""
        n = _c.lib.duet_runtime_get_path(self.handle, None, 0, 0)
        out = np.empty((n, 2), dtype=np.float32)
        got = _c.lib.duet_runtime_get_path(self.handle, out.ctypes.data_as(ctypes.POINTER(ctypes.c_float)), 0, n)
        self._check()
        return out[:min(n, got)]

    def grid(self):
        h = _c.lib.duet_runtime_get_grid(self.handle)
        self._check()
        return Grid(h, self._device)

    def cloud(self):
        h = _c.lib.duet_runtime_get_cloud(self.handle)
        self._check()
        return Cloud(h, self._device)

    def stats(self):
        s = _c.RuntimeStats()
        _c.lib.duet_runtime_get_stats(self.handle, ctypes.byref(s))
        self._check()
        return {name: getattr(s, name) for name in _c._STATS_FIELDS}


class Sim(_Handle):
    """duet's simulator (duet_sim.h): a world, a robot from a profile, stepped with commands."""

    _release = staticmethod(_c.lib.duet_sim_release)

    def __init__(self, device, world="lab", profile="dual", sets=None, seed=1):
        kind, text = _profile(profile)
        arr, n = _sets(sets)
        h = _c.lib.duet_sim_new(device.handle, str(world).encode(), kind, text, arr, n, seed)
        _raise_pending(device.handle)
        super().__init__(h, device)
        self._info = [self.sensor_info(i) for i in range(_c.lib.duet_sim_get_sensor_count(self.handle))]

    @property
    def time(self):
        return _c.lib.duet_sim_get_time(self.handle)

    def sensor_info(self, sensor):
        si = _c.SensorInfo()
        _c.lib.duet_sim_get_sensor_info(self.handle, sensor, ctypes.byref(si))
        self._check()
        return _sensor_info(si)

    def step(self, command, dt_s):
        """Drives with command (v, omega) for dt_s seconds."""
        _c.lib.duet_sim_step(self.handle, _c.Twist(*command), dt_s)
        self._check()

    def take_frame(self, sensor):
        """(stamp_s, depth (H, W) uint16 in the sensor's units, rgb (H, W, 3) uint8), or None."""
        info = self._info[sensor]
        h, w = info["height"], info["width"]
        depth = np.empty((h, w), dtype=np.uint16)
        rgb = np.empty((h, w, 3), dtype=np.uint8)
        stamp = ctypes.c_double()
        got = _c.lib.duet_sim_take_frame(self.handle, sensor, ctypes.byref(stamp),
                                         depth.ctypes.data_as(ctypes.POINTER(ctypes.c_uint16)), 0,
                                         rgb.ctypes.data_as(ctypes.POINTER(ctypes.c_uint8)), 0, w, h)
        self._check()
        return (stamp.value, depth, rgb) if got else None

    def take_odometry(self):
        """[(stamp_s, (x, y, theta), (v, omega)), ...] waiting, oldest first."""
        out = []
        stamps = (ctypes.c_double * 64)()
        poses = (_c.Pose2 * 64)()
        twists = (_c.Twist * 64)()
        while True:
            n = _c.lib.duet_sim_take_odometry(self.handle, stamps, poses, twists, 64)
            self._check()
            out.extend((stamps[i], (poses[i].x, poses[i].y, poses[i].theta), (twists[i].v, twists[i].omega)) for i in range(n))
            if n < 64:
                return out

    @property
    def true_pose(self):
        p = _c.lib.duet_sim_get_true_pose(self.handle)
        self._check()
        return p.x, p.y, p.theta

    @property
    def collisions(self):
        return _c.lib.duet_sim_get_collisions(self.handle)

    def score(self, grid):
        """(coverage of the reachable free area in [0, 1], explored area [m^2]) of a map."""
        cov, area = ctypes.c_double(), ctypes.c_double()
        _c.lib.duet_sim_score(self.handle, grid.handle, ctypes.byref(cov), ctypes.byref(area))
        self._check()
        return cov.value, area.value


def time_now():
    """Seconds on the monotonic clock the runtime's own thread uses by default."""
    return _c.lib.duet_time_now()
