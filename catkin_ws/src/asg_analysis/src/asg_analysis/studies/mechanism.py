"""What the flawed U-Net gets wrong before its flaw findings' contacts (issue #57).

For every flaw finding (attribution `flaw`, ended in a COLLISION) of the given campaign exports,
the scene is rendered again at the vehicle's stored positions SECONDS before the contact (the
export's 10 Hz trajectory; heading from the positions around each one) with the simulator's
ground-truth labels, sun-lit map and obstacle index image (`asg_sim_dataset --poses ...
--instances 1`), and the stack under test's U-Net and the unflawed `full` U-Net label the same
camera image. Per frame, on four sets of pixels:

- `hit`: the obstacle the vehicle then hit (its pixels in the index image): the share each model
  calls non-traversable (a missed obstacle is a low share);
- `other CLASS`: the other obstacles' non-traversable pixels, by their class;
- `shadow`: traversable ground in a cast shadow (lit < 50 %): the share called non-traversable
  (a shadow read as an obstacle);
- `lit`: traversable ground in the sun, the same share.

Shares are pooled over pixels, by the class (mesh) of the obstacle hit. Frames where the hit
obstacle covers fewer than MIN_HIT_PX pixels (behind the camera, hidden) count only for the
ground rows. `python3 -m asg_analysis mechanism EXPORT... --out results/hardening/mechanism`
writes `mechanism.json`; `--doc docs/design-loop.md` writes its table between the
`<!-- mechanism:begin -->` markers (tests/test_mechanism.py checks both against the exports).
"""

import argparse
import json
import os
import subprocess
from typing import Dict, List, Sequence

import numpy as np

PROG = "python3 -m asg_analysis mechanism"

SECONDS = (4.0, 3.0, 2.0, 1.0, 0.5)  #: [s] before the contact (the trajectory's last point)
HZ = 10.0  #: [Hz] the exports' trajectory rate
MIN_HIT_PX = 50  #: [px] the hit obstacle counts as seen in a frame from this size
SHADOW_LIT = 128  #: [0..255] ground darker than this in the lit map is in a cast shadow
TRAVERSABLE, NON_TRAVERSABLE = 0, 1
FORMAT = 1


class MechanismError(Exception):
    pass


def heading(xy: np.ndarray, i: int, start_yaw: float) -> float:
    """[rad] the direction of travel at point i: from the positions 0.2 s around it, or the
    nearest ones apart where the vehicle stood; `start_yaw` where it never moved."""
    for w in range(2, len(xy)):
        d = xy[min(len(xy) - 1, i + w)] - xy[max(0, i - w)]
        if np.hypot(*d) > 1e-3:
            return float(np.arctan2(d[1], d[0]))
    return float(start_yaw)


def frame_counts(gt, lit, inst, labels: Dict[str, np.ndarray], hit: int, classes: Sequence[str]) -> dict:
    """Pixel counts of one frame: per set, its size and how many pixels each model calls
    non-traversable. `hit` is the flat index of the obstacle hit (inst holds index + 1), `classes`
    every obstacle's class (mesh) by flat index: other obstacles are counted by class."""
    cls = np.asarray([""] + list(classes))[np.minimum(inst, len(classes))]
    others = (gt == NON_TRAVERSABLE) & (inst != hit + 1) & (inst > 0)
    masks = {"hit": inst == hit + 1}
    for c in sorted(set(classes)):
        masks[f"other {c}"] = others & (cls == c)
    masks["shadow"] = (gt == TRAVERSABLE) & (lit < SHADOW_LIT)
    masks["lit"] = (gt == TRAVERSABLE) & (lit >= SHADOW_LIT)
    out = {}
    for name, m in masks.items():
        row = {"px": int(m.sum()), "gt": int((m & (gt == NON_TRAVERSABLE)).sum())}
        for model, lab in labels.items():
            row[model] = int((m & (lab == NON_TRAVERSABLE)).sum())
        out[name] = row
    return out


def findings(export_paths: Sequence[str]) -> List[dict]:
    """The flaw findings ended in a collision, with their scene, trajectory and obstacle hit."""
    from asg_agent.campaign.hardening import sources_from_export

    out = []
    for path in export_paths:
        for src in sources_from_export(path, classes=("flaw",)):
            if src.origin.get("termination") != "COLLISION" or src.origin.get("collision_with") in (None, ""):
                continue
            hit = int(src.origin["collision_with"])
            meshes = [l["mesh_name"] for l in src.request["structural"]["layouts"] for _ in l["instances"]]
            out.append(
                {
                    "campaign": src.origin["campaign"],
                    "job": src.origin["job"],
                    "hit": hit,
                    "hit_class": meshes[hit],
                    "classes": meshes,
                    "request": src.request,
                    "xy": src.trajectory,
                }
            )
    return out


def write_poses(found: List[dict], out: str) -> List[tuple]:
    """Scenario files and poses.csv for every finding's frames; returns (finding, seconds) a row."""
    from asg_scenario import dump_scenario

    os.makedirs(os.path.join(out, "scenarios"), exist_ok=True)
    rows, keys = [], []
    for k, f in enumerate(found):
        fname = f"scenarios/{k:03d}-{f['campaign']}-job{f['job']}.yaml"
        with open(os.path.join(out, fname), "w", encoding="utf-8") as fh:
            fh.write(f"# {f['campaign']} job {f['job']}: a flaw finding (issue #57 mechanism)\n")
            fh.write(dump_scenario(dict(f["request"], name=os.path.basename(fname)[:-5])))
        xy = f["xy"]
        last = len(xy) - 1
        for s in SECONDS:
            i = last - int(round(s * HZ))
            if i < 0:
                continue
            rows.append((fname, xy[i][0], xy[i][1], heading(xy, i, f["request"]["operational"]["start_yaw"])))
            keys.append((k, s))
    with open(os.path.join(out, "poses.csv"), "w", encoding="utf-8") as fh:
        fh.write("scenario,x,y,yaw\n")
        fh.writelines(f"{r[0]},{r[1]:.4f},{r[2]:.4f},{r[3]:.5f}\n" for r in rows)
    return keys


def measure(export_paths: Sequence[str], out: str, models: Dict[str, str], tool: str = "") -> dict:
    """Renders, labels and counts (module docstring); writes and returns `out`/mechanism.json."""
    import cv2

    from asg_agent.campaign.hardening import dataset_tool
    from asg_perception.inference import Segmenter

    found = findings(export_paths)
    if not found:
        raise MechanismError(f"no flaw finding ended in a collision in {', '.join(export_paths)}")
    keys = write_poses(found, out)
    frames = os.path.join(out, "frames")
    r = subprocess.run(
        [tool or dataset_tool(), "--out", frames, "--poses", os.path.join(out, "poses.csv"), "--instances", "1"],
        capture_output=True,
        text=True,
    )
    if r.returncode != 0:
        raise MechanismError(f"asg_sim_dataset failed ({r.returncode}): {r.stderr.strip()[-400:]}")
    nets = {name: Segmenter(path, "channels_last", 1) for name, path in models.items()}
    per = [dict(campaign=f["campaign"], job=f["job"], hit=f["hit"], hit_class=f["hit_class"], frames=[]) for f in found]
    for n, (k, s) in enumerate(keys):
        stem = os.path.join(frames, "images", f"{n:06d}")
        rgb = cv2.cvtColor(cv2.imread(stem + "_rgb.png", cv2.IMREAD_COLOR), cv2.COLOR_BGR2RGB)
        gt = cv2.imread(stem + "_labels.png", cv2.IMREAD_UNCHANGED)
        lit = cv2.imread(stem + "_lit.png", cv2.IMREAD_UNCHANGED)
        inst = cv2.imread(stem + "_instances.png", cv2.IMREAD_UNCHANGED)
        labels = {name: net(rgb) for name, net in nets.items()}
        per[k]["frames"].append(
            {"seconds_before": s, **frame_counts(gt, lit, inst, labels, per[k]["hit"], found[k]["classes"])}
        )
    result = {
        "format": FORMAT,
        "exports": [os.path.basename(p) for p in export_paths],
        "models": {name: os.path.basename(p) for name, p in models.items()},
        "seconds_before": list(SECONDS),
        "min_hit_px": MIN_HIT_PX,
        "shadow_lit": SHADOW_LIT,
        "findings": per,
    }
    with open(os.path.join(out, "mechanism.json"), "w", encoding="utf-8") as fh:
        json.dump(result, fh, indent=None, separators=(",", ":"))
    return result


def summary(result: dict) -> Dict[str, dict]:
    """Per class of the obstacle hit: findings, frames, and per set the pooled share of pixels
    each model (and ground truth) calls non-traversable."""
    models = list(result["models"]) + ["gt"]
    out: Dict[str, dict] = {}
    for f in result["findings"]:
        c = out.setdefault(f["hit_class"], {"findings": 0, "frames": 0, "hit_frames": 0, "sets": {}})
        c["findings"] += 1
        for fr in f["frames"]:
            c["frames"] += 1
            seen = fr["hit"]["px"] >= result["min_hit_px"]
            c["hit_frames"] += int(seen)
            for name in (k for k in fr if k != "seconds_before"):
                if name == "hit" and not seen:
                    continue
                acc = c["sets"].setdefault(name, {m: 0 for m in models + ["px"]})
                for m in models + ["px"]:
                    acc[m] += fr[name][m]
    return out


def markdown(result: dict) -> str:
    """The doc's table: per class hit and per set, the share called non-traversable."""
    models = list(result["models"])
    lines = [
        "| obstacle hit | flaw findings | frames (hit obstacle seen) | pixels | "
        + " | ".join(f"`{m}`" for m in models)
        + " | ground truth |",
        "|---|---|---|---|" + "---|" * (len(models) + 1),
    ]
    what = {"hit": "the obstacle hit", "shadow": "ground in shadow", "lit": "ground in the sun"}
    for cls, c in sorted(summary(result).items(), key=lambda kv: -kv[1]["findings"]):
        order = ["hit"] + sorted(k for k in c["sets"] if k.startswith("other ")) + ["shadow", "lit"]
        for name in order:
            acc = c["sets"].get(name)
            if not acc or not acc["px"]:
                continue
            label = what.get(name) or f"other {name[6:]} obstacles"
            shares = " | ".join(f"{100.0 * acc[m] / acc['px']:.1f} %" for m in models + ["gt"])
            lines.append(
                f"| {cls}: {label} | {c['findings']} | {c['frames']} ({c['hit_frames']}) | {acc['px']:,} | {shares} |"
            )
    return "\n".join(lines)


BEGIN = "<!-- mechanism:begin (python3 -m asg_analysis mechanism; tests/test_mechanism.py) -->"
END = "<!-- mechanism:end -->"


def write_doc(doc: str, table: str) -> None:
    """Writes the table as the page's mechanism block (the one writer, asg_analysis.docblocks)."""
    from asg_analysis.docblocks import rewrite_between

    if rewrite_between(doc, BEGIN, END, f"{BEGIN}\n{table}\n{END}", False, PROG) == 2:
        raise MechanismError(f"{doc}: no {BEGIN} ... {END} block to fill")


def run(argv=None) -> int:
    from asg_perception.segmenter_node import resolve_model

    ap = argparse.ArgumentParser(prog=PROG, description=__doc__.split("\n")[0])
    ap.add_argument("exports", nargs="+", help="campaign exports (CAMPAIGN.jsonl.gz) of the stack under test")
    ap.add_argument("--out", required=True, help="folder for scenarios, poses, frames and mechanism.json")
    ap.add_argument("--under-test", default="flawed", help="the stack under test's U-Net (name or .pt)")
    ap.add_argument("--reference", default="full", help="the unflawed U-Net (name or .pt)")
    ap.add_argument("--doc", help="a Markdown file with a mechanism block to fill with the table")
    ap.add_argument("--from-json", action="store_true", help="only redo the table from OUT/mechanism.json")
    a = ap.parse_args(argv)
    try:
        if a.from_json:
            with open(os.path.join(a.out, "mechanism.json"), encoding="utf-8") as f:
                result = json.load(f)
        else:
            models = {a.under_test: resolve_model(a.under_test), a.reference: resolve_model(a.reference)}
            result = measure(a.exports, a.out, models)
        table = markdown(result)
        print(table)
        if a.doc:
            write_doc(a.doc, table)
    except (MechanismError, OSError, ValueError) as e:
        print(f"mechanism: {e}")
        return 2
    return 0
