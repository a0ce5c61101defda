"""How far apart the labels of U-Net numerics are: backends, and oneDNN/ATen kernels (no rospy).

Each arm is BACKEND:ISA, ISA `native` (the segmenter's own cap, asg_perception.numerics.pin) or a
oneDNN ISA name such as AVX2, which caps oneDNN (ONEDNN_MAX_CPU_ISA) and ATen
(ATEN_CPU_CAPABILITY) at it, as on a CPU that has nothing above it. Every arm labels the same
frames in its own process; the table gives, for every pair of arms, the frames and pixels whose
labels differ (issue #53: the polyphase decoder against the default, next to the default against
itself on another CPU class; docs/benchmarks.md).

    python3 -m asg_perception.agreement MODEL.pt --data DIR[,DIR...] \
        [--arm channels_last:native --arm channels_last:AVX2 ...] [--frames N] [--json OUT]
"""

import argparse
import itertools
import json
import os
import subprocess
import sys
import tempfile
from typing import Dict, List, Tuple

import numpy as np

DEFAULT_ARMS = ("channels_last:native", "channels_last:AVX2", "polyphase:native", "polyphase:AVX2")


def parse_arm(text: str) -> Tuple[str, str]:
    from .numerics import BACKENDS, ISA_ORDER

    backend, _, isa = text.partition(":")
    if backend not in BACKENDS:
        raise ValueError(f"arm {text!r}: backend {backend!r} is not one of {', '.join(BACKENDS)}")
    isa = isa or "native"
    if isa != "native" and isa.upper() not in ISA_ORDER:
        raise ValueError(f"arm {text!r}: ISA {isa!r} is not 'native' or one of {', '.join(ISA_ORDER)}")
    return backend, isa if isa == "native" else isa.upper()


def arm_env(isa: str) -> Dict[str, str]:
    env = dict(os.environ)
    if isa != "native":
        env.update(ONEDNN_MAX_CPU_ISA=isa, DNNL_MAX_CPU_ISA=isa, ATEN_CPU_CAPABILITY=isa.lower())
    return env


def label_frames(model: str, data: str, frames: int, backend: str, out: str) -> str:
    """Labels of every frame (N x H x W uint8) saved to `out`; returns the segmenter's numerics."""
    from .data import load_sets
    from .inference import Segmenter
    from .numerics import identity

    rgb = load_sets(data, frames or None).rgb
    seg = Segmenter(model, backend)
    np.save(out, seg.batch(rgb))
    return identity(backend, 1)


def compare(labels: Dict[str, np.ndarray]) -> List[dict]:
    rows = []
    for a, b in itertools.combinations(labels, 2):
        d = labels[a] != labels[b]
        rows.append(
            {
                "a": a,
                "b": b,
                "frames_differ": int(d.any(axis=(1, 2)).sum()),
                "pixels_differ": int(d.sum()),
                "frames": int(d.shape[0]),
                "pixels": int(d.size),
            }
        )
    return rows


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="agreement", description=__doc__.split("\n\n")[0])
    p.add_argument("model")
    p.add_argument("--data", required=True, help="dataset folder(s), comma-separated")
    p.add_argument("--arm", action="append", help=f"BACKEND:ISA (repeatable; default {' '.join(DEFAULT_ARMS)})")
    p.add_argument("--frames", type=int, default=0, help="first N frames of each folder (0: all)")
    p.add_argument("--json", help="write the table here")
    p.add_argument("--label-only", nargs=2, metavar=("BACKEND", "OUT"), help=argparse.SUPPRESS)
    a = p.parse_args(argv)
    if a.label_only:
        print(label_frames(a.model, a.data, a.frames, a.label_only[0], a.label_only[1]))
        return 0
    try:
        arms = [parse_arm(t) for t in (a.arm or DEFAULT_ARMS)]
    except ValueError as e:
        p.error(str(e))
    if not os.path.isfile(a.model):
        p.error(f"model {a.model}: no such file")
    labels, numerics = {}, {}
    with tempfile.TemporaryDirectory() as tmp:
        for k, (backend, isa) in enumerate(arms, 1):
            name = f"{backend}:{isa}"
            out = os.path.join(tmp, f"{k}.npy")
            cmd = [sys.executable, "-m", "asg_perception.agreement", a.model, "--data", a.data]
            cmd += ["--frames", str(a.frames), "--label-only", backend, out]
            r = subprocess.run(cmd, env=arm_env(isa), capture_output=True, text=True)
            if r.returncode:
                print(f"error: arm {name} failed:\n{r.stderr.strip()}", file=sys.stderr)
                return 2
            numerics[name] = r.stdout.strip().splitlines()[-1]
            labels[name] = np.load(out)
            print(f"[{k}/{len(arms)}] {name}: {len(labels[name])} frames labelled ({numerics[name]})", flush=True)
    rows = compare(labels)
    for r in rows:
        print(
            f"  {r['a']:>22} vs {r['b']:<22} {r['frames_differ']:5d} of {r['frames']} frames, "
            f"{r['pixels_differ']:6d} of {r['pixels']:,} pixels differ"
        )
    if a.json:
        with open(a.json, "w") as f:
            json.dump(
                {"model": os.path.basename(a.model), "data": a.data, "numerics": numerics, "pairs": rows}, f, indent=1
            )
            f.write("\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
