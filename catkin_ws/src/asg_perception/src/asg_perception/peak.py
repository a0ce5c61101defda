"""How close the U-Net's inference comes to the machine: its FLOP count per frame, its ms per
frame on one core, and the single-core FP32 rate of one large convolution on the same backend, the
practical peak the U-Net's convolutions are measured against; with the nominal clock and
AVX-512 FMA width beside it (docs/benchmarks.md).

    python3 -m asg_perception.peak MODEL.pt [--repeats 5] [--json OUT]
"""

import argparse
import json
import statistics
import sys
import time

import numpy as np
import torch
from torch import nn

from .inference import Segmenter
from .train import load_model


def unet_flops(model: nn.Module, height: int = 256, width: int = 256) -> int:
    """Multiply-adds x 2 of every convolution for one frame (activations and copies left out)."""
    total = [0]

    def hook(mod, inp, out):
        k = mod.kernel_size[0] * mod.kernel_size[1] * mod.in_channels // mod.groups
        total[0] += 2 * k * out.numel()

    handles = [m.register_forward_hook(hook) for m in model.modules() if isinstance(m, nn.Conv2d)]
    with torch.no_grad():
        model(torch.zeros(1, 3, height, width))
    for h in handles:
        h.remove()
    return total[0]


def conv_peak_gflops(channels: int = 256, size: int = 64, repeats: int = 5) -> float:
    """FP32 rate of one large 3x3 convolution (NHWC, oneDNN): the practical single-core peak of the
    backend the U-Net uses (Debian's torch multiplies plain matrices with a generic BLAS, so an
    sgemm would understate it)."""
    conv = nn.Conv2d(channels, channels, 3, padding=1).to(memory_format=torch.channels_last)
    x = torch.randn(1, channels, size, size).contiguous(memory_format=torch.channels_last)
    flops = 2 * 9 * channels * channels * size * size
    times = []
    with torch.no_grad():
        conv(x)
        for _ in range(repeats):
            t0 = time.perf_counter()
            conv(x)
            times.append(time.perf_counter() - t0)
    return flops / statistics.median(times) / 1e9


def main(argv=None):
    p = argparse.ArgumentParser(prog="peak", description=__doc__.split("\n\n")[0])
    p.add_argument("model")
    p.add_argument("--frames", type=int, default=40)
    p.add_argument("--repeats", type=int, default=5)
    p.add_argument("--json", default="")
    a = p.parse_args(argv)
    torch.set_num_threads(1)
    try:
        flops = unet_flops(load_model(a.model))
        seg = Segmenter(a.model, "channels_last", 1)
    except ValueError as e:
        print(f"peak: {e}", file=sys.stderr)
        return 2
    rng = np.random.default_rng(0)
    frames = [rng.integers(0, 256, (256, 256, 3), dtype=np.uint8) for _ in range(a.frames)]
    per = []
    for _ in range(a.repeats):
        t0 = time.perf_counter()
        for f in frames:
            seg(f)
        per.append((time.perf_counter() - t0) / len(frames))
    ms = statistics.median(per) * 1000
    peak = conv_peak_gflops(repeats=a.repeats)
    out = {
        "unet_gflop_per_frame": flops / 1e9,
        "unet_ms_per_frame": ms,
        "unet_gflops": flops / 1e9 / (ms / 1000),
        "conv_peak_gflops_one_core": peak,
        "fraction_of_conv_peak": flops / 1e9 / (ms / 1000) / peak,
        "torch": torch.__version__,
    }
    print(
        f"U-Net: {out['unet_gflop_per_frame']:.2f} GFLOP a frame, {ms:.1f} ms a frame on one core "
        f"(median of {a.repeats} x {a.frames} frames) = {out['unet_gflops']:.0f} GFLOP/s; a large 3x3 "
        f"convolution on the same backend: {peak:.0f} GFLOP/s; the U-Net reaches "
        f"{out['fraction_of_conv_peak']:.0%} of it (torch {torch.__version__})"
    )
    if a.json:
        with open(a.json, "w") as f:
            json.dump(out, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
