"""Where a process's time goes: wall seconds and calls per named stage, plus the process's CPU
time (no rospy). The segmenter publishes it as asg_msgs/StageTimes; docs/benchmarks.md."""

import threading
import time
from contextlib import contextmanager


class StageClock:
    def __init__(self, stages):
        self.stages = list(stages)
        self.seconds = {s: 0.0 for s in self.stages}
        self.calls = {s: 0 for s in self.stages}
        self._lock = threading.Lock()

    @contextmanager
    def time(self, stage: str):
        if stage not in self.seconds:
            raise KeyError(f"unknown stage {stage!r}: one of {', '.join(self.stages)}")
        t0 = time.perf_counter()
        try:
            yield
        finally:
            dt = time.perf_counter() - t0
            with self._lock:
                self.seconds[stage] += dt
                self.calls[stage] += 1

    def read(self):
        """(stages, seconds, calls, process CPU seconds)."""
        with self._lock:
            return (
                list(self.stages),
                [self.seconds[s] for s in self.stages],
                [self.calls[s] for s in self.stages],
                time.process_time(),
            )
