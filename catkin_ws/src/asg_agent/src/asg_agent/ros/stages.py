"""ROS layer of `bench`: collects the asg_msgs/StageTimes readings that every scene worker,
segmenter and planner publishes on `<worker>/stage_times` (docs/benchmarks.md)."""

import threading
import time

import rospy
from asg_msgs.msg import StageTimes


def reading(msg: StageTimes) -> dict:
    return {
        "node": msg.node,
        "runs": int(msg.runs),
        "cpu_seconds": float(msg.cpu_seconds),
        "seconds": {s: float(x) for s, x in zip(msg.stages, msg.seconds)},
        "calls": {s: int(c) for s, c in zip(msg.stages, msg.calls)},
    }


class StageCollector:
    """First and latest reading of each (worker, node)."""

    def __init__(self, workers):
        self.lock = threading.Lock()
        self.first, self.last = {}, {}
        self.subs = [
            rospy.Subscriber(f"{w.rstrip('/')}/stage_times", StageTimes, self._on, callback_args=w, queue_size=16)
            for w in workers
        ]

    def _on(self, msg, worker):
        key = (worker, msg.node)
        with self.lock:
            self.first.setdefault(key, reading(msg))
            self.last[key] = reading(msg)

    def wait_for(self, expected: int, timeout: float = 10.0) -> bool:
        """Waits until `expected` (worker, node) pairs have reported (their latched first reading)."""
        end = time.time() + timeout
        while time.time() < end:
            with self.lock:
                if len(self.first) >= expected:
                    return True
            time.sleep(0.1)
        return False

    def snapshot(self):
        with self.lock:
            return dict(self.first), dict(self.last)

    def close(self):
        for s in self.subs:
            s.unregister()
