"""Held-apart sets that are held apart (issues #57, #68; no ROS): whether scenes of a set (frames
to evaluate on, a suite) also stand in a training source (a campaign export whose scenes trained a
model, a frame set, a suite), as the same layout within a tolerance. Two searches with the same
seed propose the same first scenes; two layouts whose every obstacle (same class, same order)
lies within `tol_m` along x and along y are one scene for this purpose, whatever their names or
textures.

The default tolerance is the augmentation's radius: training frames are rendered in copies of a
scene with every obstacle shifted up to `campaign.hardening.Perturbation.shift_m` along x and
along y (its one definition, imported here), so a scene within that radius of a training scene,
obstacle by obstacle and axis by axis, may be one the model was trained on. `SAME_M` (10 mm) is
the first check's tolerance (issue #57): the same layout.

    python3 -m asg_agent.campaign.overlap SET_SOURCE TRAINING_SOURCE [...] [--tol-m M]

A source is an export (`.jsonl.gz`: every stored scene), a suite folder (`suite.yaml`), or a frame
set folder (`hardening.json`: its scenes as they ran). Exit 1 with the shared scenes named.
"""

import argparse
import gzip
import json
import os
import sys
from typing import Dict, List, Sequence, Tuple

import numpy as np


#: [m] two layouts closer than this, obstacle by obstacle, are the same layout (issue #57's check)
SAME_M = 0.01
#: [m] the held-apart check's default (issue #68): the augmentation's obstacle shift, along x and
#: along y; a held-apart scene this close to a training scene may be one of its training copies
#: [m] the largest shift of an obstacle, along x and along y, with which hardening augments a
#: training frame (campaign.hardening.Perturbation.shift_m takes it from here: one definition)
AUGMENT_SHIFT_M = 0.5
TOL_M = AUGMENT_SHIFT_M

Scene = Tuple[str, Tuple[str, ...], np.ndarray]  # (label, meshes in order, n x 2 positions [m])


class OverlapError(ValueError):
    """A set shares scenes with a training source: the message names every pair."""


def request_scene(label: str, request: dict) -> Scene:
    from asg_scenario.layout import mesh_of_instances, positions

    return label, tuple(mesh_of_instances(request)), positions(request)


def scenes_of(source: str) -> List[Scene]:
    """The scenes of an export, a suite folder or a frame set folder."""
    if source.endswith(".jsonl.gz"):
        out = []
        with gzip.open(source, "rt", encoding="utf-8") as f:
            head = json.loads(f.readline()).get("campaign", {})
            for line in f:
                r = json.loads(line)
                if "job" in r and r.get("positions") is not None:
                    xy = np.asarray(r["positions"], dtype=np.float64).reshape(-1, 2)
                    out.append((f"{head.get('name', source)} job {r['job']}", tuple(r.get("meshes") or ()), xy))
        return out
    if os.path.isfile(os.path.join(source, "suite.yaml")):  # read here: campaign.suite imports this module
        import yaml
        from asg_scenario import load_scenario

        with open(os.path.join(source, "suite.yaml"), encoding="utf-8") as f:
            entries = (yaml.safe_load(f) or {}).get("scenarios") or []
        return [
            request_scene(
                f"{os.path.basename(source.rstrip('/'))}/{e['file']} ({e['campaign']} job {e['job']})",
                load_scenario(os.path.join(source, e["file"])),
            )
            for e in entries
        ]
    if os.path.isfile(os.path.join(source, "hardening.json")):
        from asg_scenario import load_scenario

        with open(os.path.join(source, "hardening.json"), encoding="utf-8") as f:
            info = json.load(f)
        out = []
        for s in info["sources"]:
            path = os.path.join(source, "scenarios", f"{s['name']}-v0.yaml")
            out.append(request_scene(f"{os.path.basename(source.rstrip('/'))}/{s['name']}", load_scenario(path)))
        return out
    raise OverlapError(f"{source}: not an export (.jsonl.gz), a suite folder or a frame set folder")


def shared(candidates: Sequence[Scene], training: Sequence[Scene], tol_m: float = TOL_M) -> List[Dict]:
    """Every (candidate, training scene) pair with the same obstacle classes in the same order and
    every obstacle within `tol_m` along x and along y; each with the largest such distance [m]."""
    groups: Dict[tuple, Tuple[List[str], np.ndarray]] = {}
    for label, meshes, xy in training:
        names, arrays = groups.setdefault((meshes, xy.shape), ([], []))
        names.append(label)
        arrays.append(xy)
    out = []
    for label, meshes, xy in candidates:
        g = groups.get((meshes, xy.shape))
        if not g:
            continue
        names, arrays = g
        dist = np.abs(np.asarray(arrays) - xy[None]).max(axis=(1, 2)) if len(xy) else np.zeros(len(names))
        for k in np.flatnonzero(dist <= tol_m):
            out.append({"scene": label, "training": names[k], "largest_m": float(dist[k])})
    return out


def check_apart(candidates: Sequence[Scene], sources: Sequence[str], what: str, tol_m: float = TOL_M) -> None:
    """OverlapError naming every scene of `candidates` that one of the training `sources` holds."""
    pairs = []
    for src in sources:
        pairs += shared(candidates, scenes_of(src), tol_m)
    if pairs:
        listed = "; ".join(f"{p['scene']} = {p['training']} (within {p['largest_m'] * 1000:.0f} mm)" for p in pairs)
        n = len({p["scene"] for p in pairs})
        raise OverlapError(f"{what}: {n} of {len(candidates)} scenes are in a training source: {listed}")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="overlap", description=__doc__.split("\n\n")[0])
    ap.add_argument("set", help="the held-apart set's source")
    ap.add_argument("training", nargs="+", help="training sources it must not share a scene with")
    ap.add_argument(
        "--tol-m",
        type=float,
        default=TOL_M,
        help=f"[m] largest obstacle distance (along x or y) of one scene (default {TOL_M:g}: the augmentation's "
        f"obstacle shift; {SAME_M:g}: the same layout)",
    )
    a = ap.parse_args(argv)
    try:
        check_apart(scenes_of(a.set), a.training, a.set, a.tol_m)
    except (OverlapError, OSError, ValueError) as e:
        print(f"overlap: {e}", file=sys.stderr)
        return 1
    print(f"{a.set}: no scene shared with {', '.join(a.training)} (tolerance {a.tol_m * 1000:g} mm)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
