#!/usr/bin/env python3
"""The ROS node end to end through a real roscore on loopback (ctest `ros_node`, Release only):

1. the simulator bridge and the node on the lab for 60 simulated seconds, everything through ROS
   topics, with faults injected by the bridge (a camera that stops for 5 s, a depth image of an
   unknown encoding and one of the wrong size, an odometry message out of order), recorded with
   `rosbag record`: the node keeps exploring (0 collisions, the map grows), counts and names each
   fault, saves its maps at the end; then `duet replay` of the bag maps the same grid;
2. the node started paused with an IMU and its mounts from tf: a ROS client (ros_probe.py) starts
   it, feeds the IMU (one NaN rate dropped and counted), reads /map, ~goal, ~path, ~frontiers
   and ~state, and calls ~return_home and ~stop; then SIGINT: it saves its maps and exits 0;
3. the launch files: duet.launch and bag.launch resolve, and duet.launch runs with a config file.
"""
import argparse
import importlib.util
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
RUN = os.path.join(ROOT, "ros", "scripts", "ros_sim_run.py")
AGREE = os.path.join(ROOT, "ros", "scripts", "grid_agreement.py")
PROBE = os.path.join(HERE, "ros_probe.py")
sys.path.insert(0, os.path.dirname(RUN))
from ros_sim_run import free_port  # noqa: E402  (a free loopback port for duet.launch's master)
# rospy is Debian's (python3-rospy): the system interpreter's, which another python3 first on the
# PATH (pyenv, a venv) may not see.
PROBE_PYTHON = sys.executable if importlib.util.find_spec("rospy") else "/usr/bin/python3"

failures = []


def check(ok, what):
    print(("ok   " if ok else "FAIL ") + what)
    if not ok:
        failures.append(what)


def run(args, **kw):
    print("$ " + " ".join(args), flush=True)
    return subprocess.run(args, **kw)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--build", required=True)
    ap.add_argument("--out", required=True)
    a = ap.parse_args()
    shutil.rmtree(a.out, ignore_errors=True)
    os.makedirs(a.out)

    # 1. Faults, a recording, the replay.
    out1 = os.path.join(a.out, "faults")
    bag = os.path.join(out1, "run.bag")
    r = run([sys.executable, RUN, "--build", a.build, "--out", out1, "--seed", "1", "--time", "60", "--sensor-rate", "5",
             "--record", bag, "--bridge", "camera_stop_at:=20", "--bridge", "camera_stop_for:=5",
             "--bridge", "malformed_at:=10", "--bridge", "odom_disorder_at:=15"])
    check(r.returncode == 0, "the node and the bridge exit 0")
    with open(os.path.join(out1, "run.json")) as f:
        res = json.load(f)
    sim, node = res["sim"], res["node"]
    check(sim.get("collisions") == 0, "0 collisions (%s)" % sim.get("collisions"))
    check(sim.get("sim_time_s", 0) >= 60.0, "the simulation ran 60 s (%s)" % sim.get("sim_time_s"))
    check(sim.get("coverage", 0) >= 0.10, "the map covers >= 10 %% of the lab after 60 s (%.1f %%)" % (100 * sim.get("coverage", 0)))
    check(sim.get("commands_received", 0) > 500, "the bridge got the node's commands (%s)" % sim.get("commands_received"))
    check(sim.get("faults", {}).get("frames_withheld", 0) > 0 and sim["faults"].get("malformed_published") == 2
          and sim["faults"].get("odometry_disordered") == 1, "the faults were injected (%s)" % sim.get("faults"))
    ros = node.get("ros", {})
    front = ros.get("sensors", [{}])[0]
    check(front.get("dropped_malformed") == 2, "both malformed depth images were dropped (%s)" % front.get("dropped_malformed"))
    check("320x240" in front.get("last_drop", ""), "the drop names what was wrong (%r)" % front.get("last_drop"))
    inp = node.get("input", {})
    check(inp.get("odometry_out_of_order", 0) >= 1, "the odometry out of order was dropped and counted (%s)" % inp.get("odometry_out_of_order"))
    check(inp.get("sensor_silences", 0) >= 1, "the stopped camera was noticed (%s)" % inp.get("sensor_silences"))
    check(node.get("sets_integrated", 0) >= 50, "the node mapped at 1 Hz (%s sets)" % node.get("sets_integrated"))
    check(ros.get("topic_to_command", {}).get("count", 0) > 500, "the node measured its topic-to-command latency (%s)"
          % ros.get("topic_to_command"))
    for f in ("grid.yaml", "grid.pgm", "cloud.pcd", "trajectory.tum", "summary.json"):
        check(os.path.isfile(os.path.join(out1, "maps", f)), "the node saved " + f)
    check(os.path.isfile(bag) and os.path.getsize(bag) > 1e6, "the bag was recorded")
    rep = os.path.join(out1, "replay")
    r = run([os.path.join(a.build, "duet"), "replay", bag, "-o", rep])  # the bag's 5 Hz is measured, not given
    check(r.returncode == 0, "duet replay of the bag exits 0")
    if r.returncode == 0:
        with open(os.path.join(rep, "summary.json")) as f:
            rate = json.load(f).get("bag", {}).get("sensor_rate_hz")
        # 1 / the median interval of the bag's (sim-clock) receipt stamps, rounded to 0.1 Hz
        check(rate is not None and abs(rate - 5.0) <= 0.1, "duet replay took the bag's camera rate, 5 Hz (%s)" % rate)
    if r.returncode == 0:
        r = run([sys.executable, AGREE, os.path.join(out1, "maps", "grid.yaml"), os.path.join(rep, "grid.yaml"),
                 "--min-agreement", "0.95", "--min-known-ratio", "0.9"], capture_output=True, text=True)
        print(r.stdout.strip())
        check(r.returncode == 0, "the replayed grid equals the node's within the pairing's differences (>= 95 % of cells known in "
              "both agree, known areas within 10 %)")
    os.remove(bag)  # ~200 MB

    # 2. SIGINT saves. This node takes the sensors' mounts from tf (the bridge publishes them as a
    #    robot description would), not from its profile.
    out2 = os.path.join(a.out, "sigint")
    #    It starts paused (autostart:=false) with an IMU (use_imu:=true); a ROS client (ros_probe.py)
    #    starts it, feeds the IMU, reads its outputs and calls its services.
    r = run([sys.executable, RUN, "--build", a.build, "--out", out2, "--seed", "2", "--time", "300", "--sensor-rate", "5",
             "--interrupt-at", "60", "--node", "mounts_from_tf:=true", "--node", "autostart:=false", "--node", "use_imu:=true",
             "--node", "map_period:=0.2", "--probe", "%s %s" % (PROBE_PYTHON, PROBE)])
    with open(os.path.join(out2, "run.json")) as f:
        res = json.load(f)
    pr = res.get("probe", {})
    print("probe: " + json.dumps(pr))
    check(res.get("probe_exit") == 0, "the ROS client ran (exit %s)" % res.get("probe_exit"))
    states = pr.get("states", [])
    check(pr.get("paused_seen") and states[:1] == ["paused"], "the node waited paused for ~start (states %s)" % states)
    check(pr.get("start", {}).get("success") and pr.get("exploring_seen"), "~start: exploring (%s)" % pr.get("start"))
    check(pr.get("map", {}).get("frame") == "map" and pr["map"].get("known", 0) > 100, "/map in the map frame (%s)" % pr.get("map"))
    check(pr.get("goal", {}).get("frame") == "map", "~goal in the map frame (%s)" % pr.get("goal"))
    check(pr.get("path", {}).get("frame") == "map" and pr["path"].get("poses", 0) >= 2, "~path: >= 2 poses (%s)" % pr.get("path"))
    check(pr.get("frontiers", {}).get("markers", 0) >= 1 and pr["frontiers"].get("frames") == ["map"],
          "~frontiers: markers in the map frame (%s)" % pr.get("frontiers"))
    check(pr.get("return_home", {}).get("success") and pr.get("returning_seen"), "~return_home: returning (%s)" % states)
    check(pr.get("stop", {}).get("success") and pr.get("stopped_seen") and states[-1:] == ["done: stopped by the operator"],
          "~stop: done, stopped by the operator (%s)" % states[-1:])
    node2 = res.get("node", {})
    check(node2.get("ros", {}).get("imu_received", 0) >= 50 and node2.get("ros", {}).get("imu_received", 0) <= pr.get("imu_published", 0),
          "the IMU was taken (%s of %s)" % (node2.get("ros", {}).get("imu_received"), pr.get("imu_published")))
    check(node2.get("gyro_invalid") == pr.get("imu_nan_published") == 1 and node2.get("gyro_pushed", 0) >= 50,
          "... its NaN yaw rate dropped and counted (%s invalid of %s)" % (node2.get("gyro_invalid"), node2.get("gyro_pushed")))
    check(res.get("node_exit") == 0, "the node interrupted by SIGINT exits 0 (%s)" % res.get("node_exit"))
    check(os.path.isfile(os.path.join(out2, "maps", "grid.pgm")), "... and saved its maps")
    check("ros" in res.get("node", {}), "... and its summary")
    with open(os.path.join(out2, "node.log")) as f:
        log = f.read()
    check("interrupted by a signal" in log, "... and said why it stopped")
    m = re.search(r"sensors\.1\.extrinsics\.zyx_euler_deg=\[([-0-9.e]+), ([-0-9.e]+), ([-0-9.e]+)\] \(from tf base_link <- kinect_right_optical\)", log)
    check(m is not None and abs(float(m.group(1)) + 90.0) < 1e-3 and abs(float(m.group(2))) < 1e-3 and abs(float(m.group(3))) < 1e-3,
          "the right Kinect's mount came from tf: yaw -90 deg as the bridge's profile (%s)" % (m.group(0) if m else "no such line"))
    check(res.get("node", {}).get("sets_integrated", 0) >= 3, "... and the node mapped with it (%s sets)"
          % res.get("node", {}).get("sets_integrated"))

    # 3. The launch files. roslaunch resolves duet.launch's and bag.launch's args, nodes and params
    #    (no master needed); then duet.launch runs (its own master on a free port) with a config
    #    file laid over the profile as ~config, until the node says which overrides it took.
    env = dict(os.environ, ROS_PACKAGE_PATH=os.path.join(a.build, "ros") + ":" + os.environ.get("ROS_PACKAGE_PATH", ""))
    cfg = os.path.join(a.out, "config.yaml")
    with open(cfg, "w") as f:
        f.write("exploration:\n  view_range_m: 3.5\n")
    r = run(["roslaunch", "--dump-params", "duet_ros", "duet.launch", "config:=" + cfg, "use_imu:=true"], env=env,
            capture_output=True, text=True, timeout=60)
    check(r.returncode == 0 and "/duet/config/exploration/view_range_m: 3.5" in r.stdout and "/duet/use_imu: true" in r.stdout,
          "duet.launch loads the config file as ~config (%s)" % (r.stdout + r.stderr).strip().replace("\n", "; "))
    r = run(["roslaunch", "--args", "/duet", "duet_ros", "duet.launch"], env=env, capture_output=True, text=True, timeout=60)
    check(r.returncode == 0 and os.path.join(a.build, "ros", "duet_ros") in r.stdout, "duet.launch runs this build's node (%s)" % r.stdout.strip())
    r = run(["roslaunch", "--nodes", "duet_ros", "bag.launch", "bag:=" + cfg], env=env, capture_output=True, text=True, timeout=60)
    check(r.returncode == 0 and sorted(r.stdout.split()) == ["/duet", "/play"], "bag.launch: rosbag play and the node (%s)" % r.stdout.split())
    r = run(["roslaunch", "--dump-params", "duet_ros", "bag.launch", "bag:=" + cfg], env=env, capture_output=True, text=True, timeout=60)
    check(r.returncode == 0 and "/use_sim_time: true" in r.stdout, "bag.launch runs on the bag's clock")
    port = free_port()
    env3 = dict(env, ROS_MASTER_URI="http://127.0.0.1:%d" % port, ROS_HOSTNAME="127.0.0.1", ROS_HOME=os.path.join(a.out, "ros_home3"),
                PYTHONUNBUFFERED="1",  # roslaunch passes the node's output on as it comes
                ROS_LOG_DIR=os.path.join(a.out, "ros_log3"))
    log3 = os.path.join(a.out, "duet_launch.log")
    with open(log3, "w") as f:
        p = subprocess.Popen(["roslaunch", "-p", str(port), "duet_ros", "duet.launch", "config:=" + cfg,
                              "output_dir:=" + os.path.join(a.out, "launch_maps")], env=env3, stdout=f, stderr=subprocess.STDOUT,
                             start_new_session=True)
        said = ""
        end = time.time() + 60.0
        while time.time() < end and p.poll() is None and "override(s)" not in said:
            time.sleep(0.5)
            with open(log3) as g:
                said = g.read()
        os.killpg(p.pid, signal.SIGINT)
        try:
            code = p.wait(30.0)
        except subprocess.TimeoutExpired:
            os.killpg(p.pid, signal.SIGKILL)
            code = p.wait()
    line = next((l for l in said.splitlines() if "override(s)" in l), "no such line")
    check("exploration.view_range_m=3.5" in line and "runtime.sensor_rate_hz=30" in line,
          "duet.launch started the node with the config file's key and the launch's sensor rate (%s)" % line.strip())
    check(code == 0, "roslaunch stopped on SIGINT (exit %s)" % code)

    print("%d checks failed" % len(failures) if failures else "all checks passed")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
