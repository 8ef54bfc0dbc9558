#!/usr/bin/env python3
"""Runs every injected fault of issue 19 on a world for several seeds and prints the table of
bench/RESULTS.md: did the run finish, collisions, coverage, the share of the grid's occupied cells
on true obstacles, how often the fault acted and what the runtime did about it.

Usage: python3 bench/fault_matrix.py [--duet build/duet] [--world lab] [--seeds 5] [--max-time 900]
                                     [--jobs 2] [--out out/faults]
Targets (issue 19): every run finishes, 0 collisions, coverage >= 90 %, >= 95 % of occupied cells
on true obstacles."""
import argparse
import concurrent.futures as cf
import json
import os
import subprocess
import sys

FAULTS = [
    "camera_stop:1@60+10", "camera_stop:2@60+10", "depth_zero:1@60+10", "depth_noise:2@60+10",
    "color_black:1@60+10", "extrinsics:2@0", "wheel_slip@60+2", "odom_jump@60", "stamp_disorder:1@60+10",
    "stamp_disorder:0@60+10", "stamp_duplicate:2@60+10", "stamp_duplicate:0@60+10", "stamp_late:1@60+10",
    "clock_back@60", "kidnap@60",
]
REACTIONS = ["odometry_invalid", "odometry_out_of_order", "odometry_jumps_absorbed", "frames_out_of_order",
             "frames_empty", "frames_garbled", "clock_restarts", "sensor_silences", "sets_with_missing_frames",
             "blind_hold_periods", "relocalizations"]


def run(args, fault, seed):
    out = os.path.join(args.out, fault.replace(":", "_").replace("@", "_at_").replace("+", "_for_"), str(seed))
    cmd = [args.duet, "explore", "-w", args.world, "-s", str(seed), "-t", str(args.max_time), "-j", "1", "-q", "-o", out]
    if fault != "none":
        cmd += ["--fault", fault]
    for kv in args.set:
        cmd += ["--set", kv]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        return fault, seed, {"error": p.stderr.strip()[-300:]}
    with open(os.path.join(out, "summary.json")) as f:
        return fault, seed, json.load(f)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--duet", default="build/duet")
    ap.add_argument("--world", default="lab")
    ap.add_argument("--seeds", type=int, default=5)
    ap.add_argument("--max-time", type=float, default=900)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--out", default="out/faults")
    ap.add_argument("--faults", default=",".join(["none"] + FAULTS))
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                    help="a profile key for every run (duet explore --set), repeatable")
    args = ap.parse_args()
    faults = args.faults.split(",")
    results = {}
    with cf.ThreadPoolExecutor(args.jobs) as ex:
        for fault, seed, s in ex.map(lambda fs: run(args, *fs), [(f, k) for f in faults for k in range(1, args.seeds + 1)]):
            results.setdefault(fault, {})[seed] = s
    print("| fault | finished | collisions | coverage min / mean | occupied on obstacles min | fault acted | the runtime's reaction (sum over seeds) |")
    print("|---|---|---|---|---|---|---|")
    ok_all = True
    for fault in faults:
        runs = [results[fault][k] for k in sorted(results[fault])]
        errors = [r["error"] for r in runs if "error" in r]
        if errors:
            print(f"| {fault} | ERROR: {errors[0]} | | | | | |")
            ok_all = False
            continue
        finished = sum(r["stop_reason"] == "explorer_done" for r in runs)
        coll = sum(r["collisions"] for r in runs)
        cov = [r["coverage"] for r in runs]
        occ = [r["occupied_cells_on_obstacles"] or 0.0 for r in runs]
        acted = sum(sum(f["injected"] for f in r["faults"]) for r in runs)
        react = {k: sum(r["input"][k] for r in runs) for k in REACTIONS}
        react_s = ", ".join(f"{k} {v}" for k, v in react.items() if v)
        ok = finished == len(runs) and coll == 0 and min(cov) >= 0.9 and min(occ) >= 0.95
        ok_all &= ok
        print(f"| {fault} | {finished}/{len(runs)} | {coll} | {100*min(cov):.1f} / {100*sum(cov)/len(cov):.1f} % | "
              f"{100*min(occ):.1f} % | {acted} | {react_s or '-'} |{'' if ok else ' **target missed**'}")
    with open(os.path.join(args.out, "matrix.json"), "w") as f:
        json.dump(results, f, indent=1)
    return 0 if ok_all else 1


if __name__ == "__main__":
    sys.exit(main())
