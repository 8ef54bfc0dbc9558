#!/usr/bin/env python3
"""Runs duet through ROS topics only: roscore on loopback (its own port), use_sim_time, the
simulator bridge (duet_sim_ros) and the node (duet_ros), optionally `rosbag record` of the node's
input topics. Writes OUT/sim.json (the bridge: coverage, collisions), OUT/maps/ (the node's saved
maps and summary.json with its "ros" block) and OUT/run.json (both, plus exit codes), and prints
one line. Used by the ROS tests (tests/ros/) and the README's ROS section.

  ros/scripts/ros_sim_run.py --out out/ros1 --seed 1 --time 60 --sensor-rate 5
  ros/scripts/ros_sim_run.py --out out/ros1 --time 900 --exit-when-done --record out/ros1/run.bag
"""
import argparse
import json
import os
import random
import signal
import socket
import subprocess
import sys
import time
import xmlrpc.client

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))


def free_port():
    """A free loopback port below the kernel's ephemeral range. A port from bind(0) is ephemeral: once
    it is closed, the next process to bind port 0 can get it back - roscore's own roslaunch server
    did, in CI (stop 43): rosmaster could not bind, and the master URI answered "getSystemState is not
    supported". Ports below the ephemeral range are only ever taken on purpose."""
    low = 32768
    try:
        with open("/proc/sys/net/ipv4/ip_local_port_range") as f:
            low = int(f.read().split()[0])
    except (OSError, ValueError, IndexError):
        pass
    rng = random.Random(os.getpid() ^ int(time.time() * 1e6))
    for _ in range(200):
        port = rng.randrange(max(1024, low - 12000), low)
        s = socket.socket()
        try:
            s.bind(("127.0.0.1", port))
            return port
        except OSError:
            continue
        finally:
            s.close()
    raise RuntimeError("no free loopback port below %d after 200 tries" % low)


class NotOurMaster(RuntimeError):
    pass


def wait_master(uri, core=None, timeout=30.0):
    """Waits until a ROS master answers at uri. Raises NotOurMaster if roscore exited or something
    that is not a master answers there (the caller then tries another port)."""
    end = time.time() + timeout
    master = xmlrpc.client.ServerProxy(uri)
    while time.time() < end:
        if core is not None and core.poll() is not None:
            raise NotOurMaster("roscore exited (%s) before its master answered at %s" % (core.returncode, uri))
        try:
            code, _, _ = master.getSystemState("/ros_sim_run")
            if code == 1:
                return master
        except xmlrpc.client.Fault as e:
            raise NotOurMaster("%s answers, but it is not a ROS master: %s" % (uri, e.faultString))
        except OSError:
            pass
        time.sleep(0.2)
    raise RuntimeError("roscore did not come up at " + uri)


def stop(proc, sig=signal.SIGINT, wait=20.0):
    if proc is None or proc.poll() is not None:
        return proc.returncode if proc else None
    try:
        os.killpg(proc.pid, sig)
    except ProcessLookupError:
        return proc.returncode
    try:
        return proc.wait(wait)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        return proc.wait()


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", required=True)
    ap.add_argument("--build", default=os.path.join(ROOT, "build"))
    ap.add_argument("--world", default="lab")
    ap.add_argument("--profile", default="dual")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--time", type=float, default=60.0, help="simulated seconds the node runs (then it saves and exits)")
    ap.add_argument("--sensor-rate", type=float, default=10.0, help="frames per second per camera (a Kinect: 30; sim.launch: 10)")
    ap.add_argument("--speed", type=float, default=1.0, help="simulated seconds per wall second")
    ap.add_argument("--exit-when-done", action="store_true", help="the node saves and exits once the explorer is done")
    ap.add_argument("--record", help="rosbag record the node's input topics into this .bag")
    ap.add_argument("--interrupt-at", type=float, help="send the node SIGINT after this many wall seconds (or, with --probe, "
                    "as soon as the probe is done)")
    ap.add_argument("--call-save-at", type=float, action="append", default=[],
                    help="call the node's ~save service after this many wall seconds (repeatable)")
    ap.add_argument("--bridge-bin", help="the duet_sim_ros to run (default: BUILD/ros/duet_sim_ros)")
    ap.add_argument("--bridge", action="append", default=[], help="extra bridge parameter NAME:=VALUE")
    ap.add_argument("--node", action="append", default=[], help="extra node parameter NAME:=VALUE")
    ap.add_argument("--node-set", action="append", default=[], help="profile override KEY=VALUE for the node")
    ap.add_argument("--probe", help="a command run (through the shell, with this run's ROS_MASTER_URI) once the bridge has "
                    "started; its standard output, a JSON object, goes into run.json's \"probe\"")
    ap.add_argument("--sensors", default="kinect_front,kinect_right", help="the profile's sensor names (for --record)")
    a = ap.parse_args()

    out = os.path.abspath(a.out)
    os.makedirs(out, exist_ok=True)
    env = dict(os.environ)
    env.update(ROS_HOSTNAME="127.0.0.1", ROS_IP="127.0.0.1",
               ROS_HOME=os.path.join(out, "ros_home"), ROS_LOG_DIR=os.path.join(out, "ros_log"))
    logs = {}

    def start(name, cmd):
        logs[name] = open(os.path.join(out, name + ".log"), "w")
        return subprocess.Popen(cmd, env=env, stdout=logs[name], stderr=subprocess.STDOUT, start_new_session=True)

    core = bridge = node = bag = None
    result = {"master_attempts": []}
    try:
        for attempt in range(4):
            port = free_port()
            env["ROS_MASTER_URI"] = "http://127.0.0.1:%d" % port
            core = start("roscore", ["roscore", "-p", str(port)])
            try:
                master = wait_master(env["ROS_MASTER_URI"], core)
                break
            except NotOurMaster as e:
                result["master_attempts"].append(str(e))
                print("ros_sim_run: %s; trying another port" % e, file=sys.stderr)
                stop(core, signal.SIGINT)
                core = None
        else:
            raise RuntimeError("no ROS master came up in 4 tries: " + "; ".join(result["master_attempts"]))
        result["port"] = port
        master.setParam("/ros_sim_run", "/use_sim_time", True)
        sets = ["runtime.sensor_rate_hz=%g" % a.sensor_rate] + a.node_set
        if a.record:
            topics = ["/odom"]
            for s in a.sensors.split(","):
                topics += ["/%s/depth_registered/image_raw" % s, "/%s/rgb/image_rect_color" % s, "/%s/rgb/camera_info" % s]
            bag = start("rosbag", ["rosbag", "record", "--lz4", "--tcpnodelay", "-O", os.path.abspath(a.record)] + topics)
            time.sleep(2.0)  # rosbag subscribes before the simulation starts
        node = start("node", [os.path.join(a.build, "ros", "duet_ros"), "_profile:=" + a.profile, "_seed:=%d" % a.seed,
                              "_output_dir:=" + os.path.join(out, "maps"), "_max_time:=%g" % a.time, "_set:=" + ";".join(sets),
                              "_exit_when_done:=%s" % ("true" if a.exit_when_done else "false")] + ["_" + p for p in a.node])
        time.sleep(1.0)
        bridge = start("bridge", [a.bridge_bin or os.path.join(a.build, "ros", "duet_sim_ros"), "_world:=" + a.world, "_profile:=" + a.profile,
                                  "_seed:=%d" % a.seed, "_sensor_rate:=%g" % a.sensor_rate, "_speed:=%g" % a.speed,
                                  "_max_time:=%g" % (a.time + 3.0), "_summary:=" + os.path.join(out, "sim.json")] + ["_" + p for p in a.bridge])
        probe = None
        if a.probe:
            probe = subprocess.Popen(a.probe, shell=True, env=env, stdout=subprocess.PIPE, stderr=logs.setdefault(
                "probe", open(os.path.join(out, "probe.log"), "w")), text=True, start_new_session=True)
        wall0 = time.time()
        limit = (a.time / a.speed if a.speed > 0 else a.time) * 2.0 + 60.0
        interrupted = False
        saves = sorted(a.call_save_at)
        result["save_calls"] = []
        while node.poll() is None and time.time() - wall0 < limit:
            probe_done = probe is not None and probe.poll() is not None
            if a.interrupt_at is not None and not interrupted and (time.time() - wall0 >= a.interrupt_at or probe_done):
                os.killpg(node.pid, signal.SIGINT)
                interrupted = True
            if saves and time.time() - wall0 >= saves[0]:
                saves.pop(0)
                call = subprocess.run(["rosservice", "call", "/duet/save"], env=env, capture_output=True, text=True, timeout=60)
                result["save_calls"].append({"exit": call.returncode, "output": (call.stdout + call.stderr).strip()})
            if bridge.poll() is not None and bridge.returncode != 0:
                break
            time.sleep(0.2)
        result["node_exit"] = node.wait(30.0) if node.poll() is None and interrupted else node.poll()
        if result["node_exit"] is None:
            result["node_exit"] = stop(node)
            result["node_timed_out"] = True
        if probe is not None:
            try:
                text, _ = probe.communicate(timeout=30.0)
            except subprocess.TimeoutExpired:
                stop(probe, signal.SIGKILL)
                text = ""
            result["probe_exit"] = probe.returncode
            try:
                result["probe"] = json.loads(text) if text.strip() else {"error": "no output"}
            except ValueError as e:
                result["probe"] = {"error": "not JSON: %s: %r" % (e, text[:200])}
        result["bridge_exit"] = stop(bridge)
        result["wall_s"] = time.time() - wall0
    finally:
        stop(bag)
        stop(node)
        stop(bridge)
        stop(core, signal.SIGINT)
        for f in logs.values():
            f.close()
    for name, path in (("sim", os.path.join(out, "sim.json")), ("node", os.path.join(out, "maps", "summary.json"))):
        try:
            with open(path) as f:
                result[name] = json.load(f)
        except (OSError, ValueError) as e:
            result[name] = {"error": str(e)}
    with open(os.path.join(out, "run.json"), "w") as f:
        json.dump(result, f, indent=1)
    sim, ros = result["sim"], result["node"].get("ros", {})
    print("ros_sim_run: node exit %s, bridge exit %s; t = %.1f s, coverage %.1f %%, %s collisions; topic->command p99 %.2f ms; %s"
          % (result.get("node_exit"), result.get("bridge_exit"), sim.get("sim_time_s", -1), 100.0 * sim.get("coverage", -1),
             sim.get("collisions", "?"), ros.get("topic_to_command", {}).get("p99_ms", -1), out))
    return 0 if result.get("node_exit") == 0 and result.get("bridge_exit") == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
