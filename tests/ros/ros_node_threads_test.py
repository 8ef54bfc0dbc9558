#!/usr/bin/env python3
"""The node's own threads under ThreadSanitizer (ctest `ros_node_threads`, TSan build only):
the node of this build (its control thread, its publishing thread, ROS's spinner threads and the
C API runtime's background work) drives a Release build's simulator bridge through a real
roscore for 25 simulated seconds at 5 Hz per camera, while its ~save service is called twice
from outside (a save on a service thread while control and publishing run); then it stops at
~max_time and saves again. TSAN_OPTIONS=halt_on_error=1 turns any report into a non-zero exit.
"""
import argparse
import json
import os
import shutil
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
RUN = os.path.join(ROOT, "ros", "scripts", "ros_sim_run.py")

failures = []


def check(ok, what):
    print(("ok   " if ok else "FAIL ") + what)
    if not ok:
        failures.append(what)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--build", required=True)
    ap.add_argument("--bridge-bin", required=True)
    ap.add_argument("--out", required=True)
    a = ap.parse_args()
    shutil.rmtree(a.out, ignore_errors=True)
    os.makedirs(a.out)
    if not os.access(a.bridge_bin, os.X_OK):
        print("FAIL the Release build's simulator bridge is missing: " + a.bridge_bin)
        return 1
    # Debian's ROS libraries are not instrumented: their own memory accesses through interceptors
    # (memcpy, free of messages they made) are not reported; the node's code stays checked.
    os.environ["TSAN_OPTIONS"] = os.environ.get("TSAN_OPTIONS", "") + ":ignore_noninstrumented_modules=1"
    cmd = [sys.executable, RUN, "--build", a.build, "--bridge-bin", a.bridge_bin, "--out", a.out, "--seed", "3",
           "--time", "25", "--sensor-rate", "5", "--call-save-at", "10", "--call-save-at", "16",
           # duet's TBB work in a one-thread arena: Debian's libtbb is not instrumented (tests/tsan.supp)
           "--node", "threads:=1", "--node-set", "runtime.background_threads=1"]
    print("$ " + " ".join(cmd), flush=True)
    r = subprocess.run(cmd)
    with open(os.path.join(a.out, "run.json")) as f:
        res = json.load(f)
    with open(os.path.join(a.out, "node.log"), errors="replace") as f:
        log = f.read()
    reports = log.count("WARNING: ThreadSanitizer")
    if reports:
        i = log.index("WARNING: ThreadSanitizer")
        print(log[i:i + 6000])
    check(reports == 0, "no ThreadSanitizer report (%d)" % reports)
    check(r.returncode == 0 and res.get("node_exit") == 0, "the node exits 0 (%s)" % res.get("node_exit"))
    calls = res.get("save_calls", [])
    check(len(calls) == 2 and all(c["exit"] == 0 and "success: True" in c["output"] for c in calls),
          "both ~save calls while it ran succeeded (%s)" % calls)
    node = res.get("node", {})
    check(node.get("sets_integrated", 0) >= 5, "the node mapped (%s sets)" % node.get("sets_integrated"))
    check(node.get("ros", {}).get("topic_to_command", {}).get("count", 0) > 100, "the control thread ran (%s)"
          % node.get("ros", {}).get("topic_to_command"))
    check(res.get("sim", {}).get("commands_received", 0) > 100, "the bridge got its commands (%s)" % res.get("sim", {}).get("commands_received"))
    check(os.path.isfile(os.path.join(a.out, "maps", "grid.pgm")), "the maps were saved")
    print("%d checks failed" % len(failures) if failures else "all checks passed")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
