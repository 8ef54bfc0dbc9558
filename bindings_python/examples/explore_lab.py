#!/usr/bin/env python3
"""A small exploration driven from Python: duet's simulator stands in for the robot, the runtime
explores, every control period goes through the C API (as bindings_c/examples/robot_loop.c).

Usage: explore_lab.py [WORLD [SEED [MAX_TIME_S [OUT_DIR]]]]   (default: lab 1 120)
"""
import sys

import duet


def main(argv):
    world = argv[1] if len(argv) > 1 else "lab"
    seed = int(argv[2]) if len(argv) > 2 else 1
    max_time = float(argv[3]) if len(argv) > 3 else 120.0
    out = argv[4] if len(argv) > 4 else None
    sets = ["runtime.sensor_rate_hz=1"]  # render only the frames the mapper takes, as duet explore
    dev = duet.Device()
    sim = duet.Sim(dev, world, "dual", sets, seed)
    rt = duet.Runtime(dev, "dual", sets, seed)
    rt.set_time_origin(0.0)  # the simulator's clock starts at 0
    rt.set_event_callback(lambda t, m: print(f"[{t:7.2f} s] {m}", file=sys.stderr))
    dt = rt.control_period
    t, cmd = 0.0, (0.0, 0.0)
    while True:
        sim.step(cmd, dt)
        t = t + dt
        for stamp, pose, twist in sim.take_odometry():
            rt.push_odometry(stamp, pose, twist)
        for i in range(rt.sensor_count):
            while (frame := sim.take_frame(i)) is not None:
                rt.push_rgbd(i, *frame)
        rt.spin_once(t)
        cmd = rt.command()
        if rt.status()["state"] == "done" or t + 1e-9 >= max_time:
            break
    coverage, explored = sim.score(rt.grid())
    print(f"time_s: {t:.2f}")
    print(f"state: {rt.status()['state']}")
    print(f"stop_detail: {rt.stop_detail()}")
    print(f"coverage: {coverage:.4f}")
    print(f"explored_m2: {explored:.2f}")
    print(f"collisions: {sim.collisions}")
    if out:
        rt.save(out)
        print(f"saved: {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
