"""Tests of the Python package over libduet.so (run by ctest: `python_bindings`)."""
import os
import subprocess
import sys

import numpy as np
import pytest

import duet

HERE = os.path.dirname(os.path.abspath(__file__))
DATA = os.environ.get("DUET_DATA_DIR", os.path.join(HERE, "..", "..", "..", "shared", "data"))
SETS = ["runtime.sensor_rate_hz=1"]


@pytest.fixture
def dev():
    d = duet.Device("threads=2")
    yield d
    d.release()


def loop(dev, seconds, seed=1):
    sim = duet.Sim(dev, "lab", "dual", SETS, seed)
    rt = duet.Runtime(dev, "dual", SETS, seed)
    rt.set_time_origin(0.0)
    t, cmd, dt = 0.0, (0.0, 0.0), rt.control_period
    while t + 1e-9 < seconds:
        sim.step(cmd, dt)
        t = t + dt
        for stamp, pose, twist in sim.take_odometry():
            rt.push_odometry(stamp, pose, twist)
        for i in range(rt.sensor_count):
            while (frame := sim.take_frame(i)) is not None:
                rt.push_rgbd(i, *frame)
        rt.spin_once(t)
        cmd = rt.command()
    return sim, rt, t


def test_version():
    assert duet.version().count(".") == 2


def test_explores_through_the_simulator_api(dev):
    sim, rt, t = loop(dev, 20.0)
    st = rt.status()
    assert st["state"] == "exploring"
    assert st["map_updates"] == 21
    assert st["health"] == "good"
    assert sim.collisions == 0
    grid = rt.grid()
    h, w = grid.shape
    assert h > 10 and w > 10
    lo = grid.logodds()
    assert lo.shape == (h, w) and lo.dtype == np.float32
    assert np.isnan(lo).any() and np.isfinite(lo).any()  # unknown and known cells
    ros = grid.ros()
    assert set(np.unique(ros)) <= {-1, 0, 100}
    # classified free or occupied at 0.45 / 0.65: a subset of the observed (non-NaN) cells
    assert 0.9 * grid.known_cells < (ros != -1).sum() <= grid.known_cells
    assert (ros != -1).sum() == np.isfinite(lo).sum() - ((lo > -0.2007) & (lo < 0.6190)).sum()
    coverage, area = sim.score(grid)
    assert 0.05 < coverage <= 1.0 and area > 5.0
    cloud = rt.cloud()
    pts = cloud.points()
    assert pts.shape == (len(cloud), 3) and len(cloud) > 1000
    assert cloud.colors().shape == (len(cloud), 3)
    path = rt.path()
    assert path.shape[1] == 2
    x, y, _ = st["pose"]
    tx, ty, _ = sim.true_pose
    assert abs(x - tx) < 0.2 and abs(y - ty) < 0.2
    s = rt.stats()
    assert s["control_periods"] == 400 and s["frames_pushed"] == 42


def test_same_trajectory_as_the_c_program(dev, tmp_path):
    """The Python loop and robot_loop.c drive the same lockstep run."""
    robot_loop = os.environ.get("DUET_ROBOT_LOOP")
    if not robot_loop:
        pytest.skip("DUET_ROBOT_LOOP not set (ctest sets it)")
    subprocess.run([robot_loop, "lab", "1", "10", str(tmp_path / "c")], check=True, capture_output=True,
                   env={**os.environ, "ROBOT_LOOP_QUIET": "1"})
    _, rt, _ = loop(dev, 10.0)
    rt.save(tmp_path / "py")
    assert (tmp_path / "c" / "trajectory.tum").read_text() == (tmp_path / "py" / "trajectory.tum").read_text()
    assert (tmp_path / "c" / "grid.pgm").read_bytes() == (tmp_path / "py" / "grid.pgm").read_bytes()


def test_errors_carry_the_c_message(dev):
    with pytest.raises(duet.DuetError) as e:
        duet.Runtime(dev, "dual", ["runtime.control_rate_hz=-1"])
    assert "control_rate_hz" in str(e.value)
    with pytest.raises(duet.DuetError) as e:
        duet.Sim(dev, "/nonexistent/world.yaml")
    assert "/nonexistent/world.yaml" in str(e.value)
    rt = duet.Runtime(dev, "dual", SETS)
    with pytest.raises(duet.DuetError) as e:
        rt.push_rgbd(0, 1.0, np.zeros((240, 320), dtype=np.uint16))  # the sensor is 640 x 480
    assert e.value.code == "INVALID_ARGUMENT" and "640 x 480" in str(e.value)
    with pytest.raises(duet.DuetError):
        rt.push_rgbd(7, 1.0, np.zeros((480, 640), dtype=np.uint16))
    with pytest.raises(ValueError):
        rt.push_rgbd(0, 1.0, np.zeros((480, 640, 2), dtype=np.uint16))
    with pytest.raises(duet.DuetError) as e:
        rt.return_home()  # before any control period
    assert e.value.code == "INVALID_OPERATION"
    rt.push_odometry(float("nan"), (0, 0, 0), (0, 0))  # a bad stamp is a counted drop, not an error
    rt.spin_once(10.0)
    assert rt.stats()["odometry_invalid"] == 1
    rt.release()
    with pytest.raises(duet.DuetError):
        rt.status()


def test_float_depth_and_colour(dev):
    rt = duet.Runtime(dev, "single", SETS)
    rt.set_time_origin(0.0)
    for k in range(51):
        rt.push_odometry(0.02 * k, (0, 0, 0), (0, 0))
    depth = np.full((480, 640), 2.0, dtype=np.float32)
    rgb = np.zeros((480, 640, 3), dtype=np.uint8)
    rgb[..., 0] = 200
    rt.push_rgbd(0, 0.5, depth, rgb)
    for k in range(1, 21):
        rt.spin_once(0.05 * k)
    assert rt.grid().known_cells > 100
    colors = rt.cloud().colors()
    assert colors is not None and (colors[:, 0] == 200).all()


def test_map_server_in_and_out(dev, tmp_path):
    willow = os.path.join(DATA, "maps", "willow-2010-02-18-0.10.yaml")
    if not os.path.exists(willow):
        pytest.skip("shared data not found")
    g = duet.Grid.load_map_server(dev, willow)
    assert g.shape == (608, 566) and abs(g.resolution - 0.1) < 1e-6
    g.save_map_server(tmp_path / "w.yaml")
    g2 = duet.Grid.load_map_server(dev, tmp_path / "w.yaml")
    assert (g.ros() == g2.ros()).all()
    with pytest.raises(duet.DuetError) as e:
        duet.Grid.load_map_server(dev, tmp_path / "missing.yaml")
    assert "missing.yaml" in str(e.value)


def test_example_runs():
    ex = os.path.join(HERE, "..", "examples", "explore_lab.py")
    r = subprocess.run([sys.executable, ex, "lab", "1", "15"], capture_output=True, text=True, env=os.environ)
    assert r.returncode == 0, r.stderr
    assert "collisions: 0" in r.stdout
