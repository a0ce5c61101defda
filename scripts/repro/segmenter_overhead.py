#!/usr/bin/env python3
"""Issue #53: what the segmenter node costs beyond its U-Net. The same frames, one at a time,
(a) through a running segmenter node (published on camera/image_raw inside an announced run,
each label awaited; the node's CPU from /proc) and (b) through asg_perception.inference in this
process; the two take turns ROUNDS times and the medians of CPU ms a frame are printed. If (a)
and (b) are close, the node's ROS work (rospy's (de)serialisation and transport) is not where a
campaign's CPU goes, and a node in C++ would not make it cheaper. Run by
scripts/repro/segmenter_overhead.sh (its own master)."""

import argparse
import os
import statistics
import subprocess
import sys
import threading
import time

import numpy as np


def proc_cpu(pid: int) -> float:
    """[s] user + system CPU time of a process."""
    fields = open(f"/proc/{pid}/stat").read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--frames", type=int, default=200)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--model", default="flawed")
    ap.add_argument("--backend", default="", help="U-Net backend (empty: the shipped default)")
    a = ap.parse_args()
    import rospy
    from asg_msgs.msg import ScenarioInfo
    from sensor_msgs.msg import Image

    from asg_perception.inference import Segmenter
    from asg_perception.numerics import resolve_backend
    from asg_perception.segmenter_node import resolve_model

    backend = resolve_backend(a.backend)
    node = subprocess.Popen(
        [
            "rosrun",
            "asg_perception",
            "segmenter",
            "__name:=segmenter",
            "__ns:=/w",
            f"_model:={a.model}",
            f"_backend:={backend}",
        ],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        rospy.init_node("segmenter_overhead")
        while not rospy.has_param("/w/segmenter/numerics"):
            if node.poll() is not None:
                print("segmenter_overhead: the segmenter exited", file=sys.stderr)
                return 2
            time.sleep(0.2)
        pid = node.pid  # rosrun execs the node: the same process
        pub = rospy.Publisher("/w/camera/image_raw", Image, queue_size=4, tcp_nodelay=True)
        info = rospy.Publisher("/w/scenario", ScenarioInfo, queue_size=4)
        got = threading.Event()
        rospy.Subscriber("/w/labels", Image, lambda m: got.set(), queue_size=4, tcp_nodelay=True)
        base = rospy.Time(ScenarioInfo.RUN_WINDOW * 10)
        while pub.get_num_connections() == 0:
            time.sleep(0.1)
        for _ in range(8):
            info.publish(ScenarioInfo(scenario_id=1, run=1, base_stamp=base, camera_width=256, camera_height=256))
            time.sleep(0.25)
        rng = np.random.default_rng(0)
        frames = [rng.integers(0, 255, (256, 256, 3), dtype=np.uint8) for _ in range(16)]
        seg = Segmenter(resolve_model(a.model), backend, 1, 256, 256)
        node_ms, local_ms, stamp = [], [], 0
        for r in range(a.rounds):
            c0 = proc_cpu(pid)
            for k in range(a.frames):
                got.clear()
                stamp += 1
                m = Image(height=256, width=256, encoding="rgb8", step=768, data=frames[k % 16].tobytes())
                m.header.stamp = base + rospy.Duration(0.1 * stamp)
                pub.publish(m)
                if not got.wait(10.0):
                    print(f"segmenter_overhead: no labels for frame {k}", file=sys.stderr)
                    return 2
            node_ms.append(1000.0 * (proc_cpu(pid) - c0) / a.frames)
            t0 = time.process_time()
            for k in range(a.frames):
                seg(np.frombuffer(frames[k % 16].tobytes(), np.uint8).reshape(256, 256, 3))
            local_ms.append(1000.0 * (time.process_time() - t0) / a.frames)
            print(f"round {r + 1}: node {node_ms[-1]:.2f} ms CPU a frame, U-Net alone {local_ms[-1]:.2f}")
        n, u = statistics.median(node_ms), statistics.median(local_ms)
        print(
            f"median of {a.rounds} rounds of {a.frames} frames ({backend}): segmenter node {n:.2f} ms CPU a frame, "
            f"the U-Net alone {u:.2f}: the node's ROS work {n - u:+.2f} ms ({100 * (n - u) / u:+.0f} %)"
        )
        return 0
    finally:
        node.terminate()
        node.wait(timeout=10)


if __name__ == "__main__":
    sys.exit(main())
