#!/usr/bin/env python3
"""A ROS client of the duet node, run by ros_sim_run.py --probe in ctest `ros_node` (part 2), with a
node started with autostart:=false and use_imu:=true. It checks what a user's stack sees:

1. the node waits, paused, for ~start (its latched ~state says "paused");
2. ~start: it explores ("exploring"); an IMU on /imu (the odometry's yaw rate, as a gyro would
   give it, at the odometry's stamps; one message with a NaN rate, which the node must drop and
   count) is taken;
3. its latched outputs arrive in the map frame: /map, ~goal, ~path (>= 2 poses), ~frontiers;
4. ~return_home: it drives home ("returning_home", or already "done" at home);
5. ~stop: "done: stopped by the operator".

Prints one JSON object (what it saw); ros_node_test.py judges it. Exit 0 unless rospy failed.
"""
import json
import math
import sys
import time

import rospy
from geometry_msgs.msg import PoseStamped
from nav_msgs.msg import OccupancyGrid, Odometry, Path
from sensor_msgs.msg import Imu
from std_msgs.msg import String
from std_srvs.srv import Trigger
from visualization_msgs.msg import MarkerArray


def wait_for(pred, timeout):
    end = time.time() + timeout
    while time.time() < end:
        if pred():
            return True
        time.sleep(0.05)
    return pred()


def main():
    rospy.init_node("duet_probe", anonymous=True, disable_signals=True)
    out = {"states": [], "imu_published": 0, "imu_nan_published": 0}
    got = {}

    def keep(name):
        def cb(m):
            got[name] = m
        return cb

    rospy.Subscriber("/duet/state", String, lambda m: out["states"].append(m.data))
    rospy.Subscriber("/duet/goal", PoseStamped, keep("goal"))
    rospy.Subscriber("/duet/path", Path, keep("path"))
    rospy.Subscriber("/duet/frontiers", MarkerArray, keep("frontiers"))
    rospy.Subscriber("/map", OccupancyGrid, keep("map"))
    imu_pub = rospy.Publisher("/imu", Imu, queue_size=100)
    imu_on = [False]

    def on_odom(m):
        if not imu_on[0]:
            return
        i = Imu()
        i.header.stamp = m.header.stamp
        i.header.frame_id = "base_link"
        i.orientation_covariance[0] = -1.0  # no orientation
        i.angular_velocity.z = m.twist.twist.angular.z
        if out["imu_published"] == 25:
            i.angular_velocity.z = float("nan")
            out["imu_nan_published"] += 1
        imu_pub.publish(i)
        out["imu_published"] += 1

    rospy.Subscriber("/odom", Odometry, on_odom)

    def call(name):
        rospy.wait_for_service(name, timeout=30.0)
        r = rospy.ServiceProxy(name, Trigger)()
        return {"success": r.success, "message": r.message}

    out["paused_seen"] = wait_for(lambda: "paused" in out["states"], 30.0)
    time.sleep(1.0)
    out["start"] = call("/duet/start")
    imu_on[0] = True
    out["exploring_seen"] = wait_for(lambda: "exploring" in out["states"], 10.0)
    wait_for(lambda: all(k in got for k in ("goal", "path", "frontiers", "map")) and out["imu_published"] >= 100, 15.0)
    if "goal" in got:
        out["goal"] = {"frame": got["goal"].header.frame_id, "x": got["goal"].pose.position.x, "y": got["goal"].pose.position.y}
    if "path" in got:
        out["path"] = {"frame": got["path"].header.frame_id, "poses": len(got["path"].poses)}
    if "frontiers" in got:
        out["frontiers"] = {"markers": len(got["frontiers"].markers),
                            "frames": sorted({mk.header.frame_id for mk in got["frontiers"].markers})}
    if "map" in got:
        m = got["map"]
        out["map"] = {"frame": m.header.frame_id, "width": m.info.width, "height": m.info.height,
                      "known": sum(1 for v in m.data if v >= 0), "finite_origin": math.isfinite(m.info.origin.position.x)}
    imu_on[0] = False
    out["return_home"] = call("/duet/return_home")
    out["returning_seen"] = wait_for(lambda: any(s == "returning_home" or s.startswith("done") for s in out["states"]), 10.0)
    out["stop"] = call("/duet/stop")
    out["stopped_seen"] = wait_for(lambda: any("stopped by the operator" in s for s in out["states"]), 10.0)
    print(json.dumps(out))
    return 0


if __name__ == "__main__":
    sys.exit(main())
