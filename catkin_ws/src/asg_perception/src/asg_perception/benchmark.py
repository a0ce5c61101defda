"""Inference benchmark: ms per 256 x 256 frame for each backend on one core, and whether each
backend's labels equal the plain eager model's on a dataset.

    python3 -m asg_perception.benchmark MODEL.pt --data DIR [--frames 50] [--repeats 5] [--layers]
        [--backends eager,channels_last,polyphase]

--backends: only these (eager, the labels' reference, and channels_last, the speed's, always run;
under an ISA pin below AVX512-BF16, leave bf16 out: oneDNN would emulate it, 1.5 s a frame).

--layers adds each convolution of the channels_last model alone: ms, MFLOP and GFLOP/s (issue #53:
the 3-class head at full resolution is a third of the convolution time for a tenth of the FLOP).
"""

import argparse
import statistics
import sys
import time


from .data import DatasetError, load_frames
from .inference import BACKENDS, Segmenter


def main(argv=None):
    p = argparse.ArgumentParser(prog="benchmark_unet", description=__doc__.split("\n\n")[0])
    p.add_argument("model")
    p.add_argument("--data", required=True, help="dataset folder (labels compared on it)")
    p.add_argument("--frames", type=int, default=50)
    p.add_argument("--repeats", type=int, default=5)
    p.add_argument("--threads", type=int, default=1)
    p.add_argument("--layers", action="store_true", help="also time each convolution alone")
    p.add_argument("--backends", default=",".join(BACKENDS), help="comma-separated backends to run (default: all)")
    a = p.parse_args(argv)
    wanted = [b for b in a.backends.split(",") if b]
    unknown = [b for b in wanted if b not in BACKENDS]
    if unknown:
        print(f"error: --backends: unknown {', '.join(unknown)} (known: {', '.join(BACKENDS)})", file=sys.stderr)
        return 2
    backends = [b for b in BACKENDS if b in wanted or b in ("eager", "channels_last")]
    try:
        frames = load_frames(a.data, a.frames)
    except DatasetError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    reference = None
    print(
        f"{len(frames)} frames, {a.threads} thread(s), medians of {a.repeats} passes, the backends "
        "taking turns pass by pass (a load on the machine falls on all of them alike)"
    )
    segs, agree = {}, {}
    for backend in backends:
        seg = segs[backend] = Segmenter(a.model, backend, a.threads)
        labels = seg.batch(frames.rgb)
        if reference is None:
            reference = labels
        agree[backend] = (
            int((labels == reference).all(axis=(1, 2)).sum()),
            int((labels != reference).sum()),
            float((labels == reference).mean()),
        )
    times = {b: [] for b in backends}
    for _ in range(a.repeats):
        for backend, seg in segs.items():
            t0 = time.perf_counter()
            for f in frames.rgb:
                seg(f)
            times[backend].append((time.perf_counter() - t0) / len(frames) * 1000)
    base = statistics.median(times["channels_last"])
    for backend in backends:
        same, differ, share = agree[backend]
        med = statistics.median(times[backend])
        print(
            f"  {backend:>14}: {med:6.2f} ms/frame, {base / med:4.2f}x channels_last "
            f"(runs {', '.join(f'{t:.2f}' for t in times[backend])}); labels equal to eager on "
            f"{same}/{len(frames)} frames, {differ} pixels differ ({100 * share:.3f} % agree)"
        )
    if a.layers:
        layer_table(segs["channels_last"], frames.rgb[0], a.repeats)
    return 0


def layer_table(seg: Segmenter, rgb, repeats: int) -> None:
    """Each convolution of `seg`'s model run alone on its input of one frame: median ms of `repeats`
    passes of 20 calls, multiply-adds x 2 [MFLOP], and the rate [GFLOP/s]."""
    import torch

    inputs = {}

    def keep(name):
        def hook(module, args, output):  # returns None: the module's output stands
            inputs.setdefault(name, (module, args[0]))

        return hook

    hooks = [
        m.register_forward_hook(keep(name)) for name, m in seg.model.named_modules() if isinstance(m, torch.nn.Conv2d)
    ]
    seg(rgb)
    for h in hooks:
        h.remove()
    total = 0.0
    print("  each convolution alone (channels_last):")
    with torch.no_grad():
        for name, (conv, x) in inputs.items():
            ts = []
            for _ in range(repeats):
                t0 = time.perf_counter()
                for _ in range(20):
                    conv(x)
                ts.append((time.perf_counter() - t0) / 20 * 1000)
            ms = statistics.median(ts)
            total += ms
            out_px = x.shape[2] * x.shape[3] / (conv.stride[0] * conv.stride[1])
            mflop = 2 * out_px * conv.in_channels * conv.out_channels * 9 / 1e6
            print(
                f"  {name:>8} {x.shape[1]:4d} -> {conv.out_channels:4d} ch at {x.shape[3]}x{x.shape[2]}: "
                f"{ms:6.2f} ms, {mflop:6.0f} MFLOP, {mflop / ms:6.1f} GFLOP/s"
            )
    print(f"  all convolutions: {total:.2f} ms")


if __name__ == "__main__":
    sys.exit(main())
