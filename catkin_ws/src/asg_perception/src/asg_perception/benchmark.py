"""Inference benchmark: ms per 256 x 256 frame for each backend on one core, and whether each
backend's labels equal the plain eager model's on a dataset.

    python3 -m asg_perception.benchmark MODEL.pt --data DIR [--frames 50] [--repeats 5]
"""
import argparse
import statistics
import sys
import time

import numpy as np

from .data import DatasetError, load_frames
from .inference import BACKENDS, Segmenter


def main(argv=None):
    p = argparse.ArgumentParser(prog="benchmark_unet", description=__doc__.split("\n\n")[0])
    p.add_argument("model")
    p.add_argument("--data", required=True, help="dataset folder (labels compared on it)")
    p.add_argument("--frames", type=int, default=50)
    p.add_argument("--repeats", type=int, default=5)
    p.add_argument("--threads", type=int, default=1)
    a = p.parse_args(argv)
    try:
        frames = load_frames(a.data, a.frames)
    except DatasetError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    reference = None
    print(f"{len(frames)} frames, {a.threads} thread(s), medians of {a.repeats} passes")
    for backend in BACKENDS:
        seg = Segmenter(a.model, backend, a.threads)
        labels = np.stack([seg(f) for f in frames.rgb])
        if reference is None:
            reference = labels
        same = int((labels == reference).all(axis=(1, 2)).sum())
        times = []
        for _ in range(a.repeats):
            t0 = time.perf_counter()
            for f in frames.rgb:
                seg(f)
            times.append((time.perf_counter() - t0) / len(frames) * 1000)
        print(f"  {backend:>14}: {statistics.median(times):6.2f} ms/frame "
              f"(runs {', '.join(f'{t:.2f}' for t in times)}); labels equal to eager on "
              f"{same}/{len(frames)} frames, {int((labels != reference).sum())} pixels differ")
    return 0


if __name__ == "__main__":
    sys.exit(main())
