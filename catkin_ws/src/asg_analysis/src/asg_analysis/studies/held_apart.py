"""Near twins of the design loop's held-apart sets (issue #68; docs/design-loop.md, section 3):
the scenes of `heldout-findings` (the per-pixel frame set) and `suite-r4pilot` that a training
source of either round's arms holds within the augmentation's radius, the default tolerance of
`asg_agent.campaign.overlap` (`Perturbation.shift_m`: every training frame is rendered in copies
of its scene with each obstacle shifted up to that far along x and along y), and what the page's
held-apart figures become without them: the suite's outcomes are recorded per scenario; the
per-pixel evaluation files pool the frames, so the frame set is rendered again as it was built and
evaluated with and without the twins' frames (scripts/repro/heldout_twins.sh writes
results/hardening/twins/; the block shows those columns once they are there).

    python3 -m asg_analysis held-apart [results/hardening] [--doc docs/design-loop.md] [--check]
    python3 -m asg_analysis held-apart --frames-without-twins SET/frames OUT   # a dataset without them

`--doc` rewrites the page's `<!-- twins:begin -->` block; `--check` exits 1 when it is not in
step (tests/test_held_apart.py checks it too, with code of its own).
"""

import argparse
import json
import os
import re
import sys
from typing import Dict, List, Tuple

import yaml

from asg_agent.paths import REPO

PROG = "python3 -m asg_analysis held-apart"

HARD = os.path.join(REPO, "results", "hardening")
SET = "heldout-findings"
SUITE = "suite-r4pilot"
BEGIN = "<!-- twins:begin (python3 -m asg_analysis held-apart --doc docs/design-loop.md; tests/test_held_apart.py) -->"
END = "<!-- twins:end -->"
#: what rebuilds the sets at the radius (scripts/repro/harden.sh skips an output that exists)
TWINS = "twins"  # results/hardening/twins: the set rendered again, evaluated with and without the twins
RERENDERED, LEFT_OUT = "rerendered", "twins-left-out"
REBUILD = (
    "rm -r runs/harden/heldout-findings results/hardening/suite-r4pilot "
    "results/hardening/evaluation-heldout-findings-[12].json && bash scripts/repro/harden.sh"
)


def _path(p: str) -> str:
    return p if os.path.isabs(p) else os.path.join(REPO, p)


def _job(label: str) -> tuple:
    """(campaign, job) of an overlap label "CAMPAIGN job N"."""
    name, _, job = label.rpartition(" job ")
    return name, int(job)


def held_apart_sets(folder: str = HARD) -> Tuple[Dict[str, list], dict]:
    """{set: [Scene]}: the frame set's scenes (its sources, from the export it was made from) and
    the suite's, each labelled "CAMPAIGN job N"; and the frame set's record."""
    from asg_agent.campaign import overlap
    from asg_scenario import load_scenario

    with open(os.path.join(folder, f"{SET}.json"), encoding="utf-8") as f:
        made = json.load(f)
    jobs = {(s["campaign"], int(s["job"])) for s in made["sources"]}
    scenes = [sc for sc in overlap.scenes_of(_path(made["made_from"]["export"])) if _job(sc[0]) in jobs]
    with open(os.path.join(folder, SUITE, "suite.yaml"), encoding="utf-8") as f:
        entries = yaml.safe_load(f)["scenarios"]
    suite = [
        overlap.request_scene(f"{e['campaign']} job {e['job']}", load_scenario(os.path.join(folder, SUITE, e["file"])))
        for e in entries
    ]
    return {SET: scenes, SUITE: suite}, made


def measure(folder: str = HARD, tol_m: float = None) -> dict:
    """The twins of both sets at `tol_m` (default: overlap's, the augmentation's radius) among the
    training sources the frame set was built apart from, and the figures without them."""
    from asg_agent.campaign import overlap
    from asg_agent.records.export import read_export

    from asg_analysis.studies.hardening import suite_passes

    tol = overlap.TOL_M if tol_m is None else tol_m
    sets, made = held_apart_sets(folder)
    sources = [s for s in made["made_from"]["apart_from"].split(",") if s]
    twins: Dict[tuple, dict] = {}
    for src in sources:
        camp, rows = read_export(_path(src))
        cls = {int(r["job"]): r.get("attribution") or "-" for r in rows}
        training = overlap.scenes_of(_path(src))
        for name, scenes in sets.items():
            for p in overlap.shared(scenes, training, tol):
                key = _job(p["scene"]) + _job(p["training"])
                t = twins.setdefault(
                    key, {"scene": p["scene"], "training": p["training"], "largest_m": p["largest_m"], "sets": []}
                )
                t["training_class"] = cls[_job(p["training"])[1]]
                t["sets"].append(name)
    frames = {(s["campaign"], int(s["job"])): int(s["frames"]) for s in made["sources"]}
    for t in twins.values():
        t["frames"] = frames.get(_job(t["scene"]), 0)
    gone = sorted({_job(t["scene"]) for t in twins.values()})
    suite_folder = os.path.join(folder, SUITE)
    committed, without = suite_passes(suite_folder), suite_passes(suite_folder, leave_out=gone)
    with open(os.path.join(suite_folder, "suite.yaml"), encoding="utf-8") as f:
        entries = yaml.safe_load(f)["scenarios"]
    kept = [e for e in entries if (e["campaign"], int(e["job"])) not in set(gone)]
    return {
        "pixels": pixels(folder),
        "tol_m": tol,
        "training": [os.path.basename(s).replace(".jsonl.gz", "") for s in sources],
        "twins": sorted(twins.values(), key=lambda t: (_job(t["scene"]), t["training"])),
        SET: {
            "scenes": len(sets[SET]),
            "kept": sum(_job(sc[0]) not in set(gone) for sc in sets[SET]),
            "frames": int(made["frames"]),
            "frames_kept": int(made["frames"]) - sum(frames.get(j, 0) for j in set(gone)),
        },
        SUITE: {
            "scenes": len(entries),
            "kept_classes": {c: sum(e["class"] == c for e in kept) for c in sorted({e["class"] for e in kept})},
            "passed": {arm: list(committed[arm]) for arm in committed},
            "passed_without": {arm: list(without.get(arm, (0, 0))) for arm in committed},
        },
    }


def _figures(path: str) -> Dict[str, list]:
    """{arm: [obstacle IoU, shadow false-obstacle rate]} and the frame count of an evaluation file."""
    with open(path, encoding="utf-8") as f:
        e = json.load(f)
    arms = {a: [r["iou"]["non_traversable"], r["shadow_false_obstacle_rate"]] for a, r in e["results"].items()}
    return {"frames": int(e["frames"]), "arms": arms}


def pixels(folder: str = HARD):
    """The per-pixel columns of the frame set as committed (its last round's evaluation, which
    holds every arm), rendered again as built, and without the twins' frames; None until
    scripts/repro/heldout_twins.sh has written them."""
    import glob

    again = {k: os.path.join(folder, TWINS, f"evaluation-{SET}-{k}.json") for k in (RERENDERED, LEFT_OUT)}
    if not all(os.path.exists(p) for p in again.values()):
        return None
    rounds = sorted(
        glob.glob(os.path.join(folder, f"evaluation-{SET}-*.json")), key=lambda p: int(p[:-5].rsplit("-", 1)[1])
    )
    out = {"committed": _figures(rounds[-1]), **{k: _figures(p) for k, p in again.items()}}
    with open(os.path.join(folder, TWINS, f"{SET}.json"), encoding="utf-8") as f:
        made_again = json.load(f)
    with open(os.path.join(folder, f"{SET}.json"), encoding="utf-8") as f:
        made = json.load(f)
    out["same_set"] = all(made_again[k] == made[k] for k in ("sources", "frames", "seed", "perturbation"))
    return out


def without_twins(frames: str, out: str, folder: str = HARD) -> int:
    """Writes OUT/manifest.csv: the frames of a rendering of the frame set (SET/frames, beside its
    poses.csv) whose scene is not a twin at the radius, and OUT/images, a link to its images;
    returns how many frames it left out."""
    import csv

    gone = {_job(t["scene"]) for t in measure(folder)["twins"] if SET in t["sets"]}
    names = {f"-{c}-job{j}-" for c, j in gone}
    with open(os.path.join(frames, "..", "poses.csv"), newline="", encoding="utf-8") as f:
        scenes = [r["scenario"] for r in csv.DictReader(f)]
    with open(os.path.join(frames, "manifest.csv"), newline="", encoding="utf-8") as f:
        rows = list(csv.DictReader(f))
    if len(scenes) != len(rows):
        raise ValueError(f"{frames}: {len(rows)} frames against {len(scenes)} poses")
    keep = [r for r, sc in zip(rows, scenes) if not any(n in os.path.basename(sc) for n in names)]
    os.makedirs(out, exist_ok=True)
    with open(os.path.join(out, "manifest.csv"), "w", newline="", encoding="utf-8") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(keep)
    link = os.path.join(out, "images")
    if not os.path.islink(link):
        os.symlink(os.path.relpath(os.path.join(frames, "images"), out), link)
    return len(rows) - len(keep)


def _arms(result: dict) -> List[str]:
    from asg_analysis.studies.hardening import _order

    return sorted(result[SUITE]["passed"], key=_order)


def markdown(result: dict) -> str:
    """The page's block: the twins, then the held-apart figures without them."""
    tol_mm = result["tol_m"] * 1000
    hs, su = result[SET], result[SUITE]
    lines = [
        f"Twins at the augmentation's radius ({tol_mm:g} mm along x and along y, obstacle by obstacle), "
        f"against the training sources of both rounds' arms ({', '.join(result['training'])}):",
        "",
        "| held-apart scene | in | its twin | the twin's class there | largest shift |",
        "|---|---|---|---|---|",
    ]
    for t in result["twins"]:
        where = ", ".join(
            f"{s} ({t['frames']} of its {hs['frames']} frames)" if s == SET else s for s in sorted(set(t["sets"]))
        )
        lines.append(
            f"| {t['scene']} | {where} | {t['training']} | {t['training_class']} | {t['largest_m'] * 1000:.0f} mm |"
        )
    if not result["twins"]:
        lines.append("| none | | | | |")
    kept = ", ".join(f"{n} {c}" for c, n in su["kept_classes"].items())
    lines += [
        "",
        f"Left out: `{SET}` keeps {hs['kept']} of its {hs['scenes']} scenes ({hs['frames_kept']} of its "
        f"{hs['frames']} frames); "
        + (
            "its per-pixel columns, from the set rendered again as it was built and evaluated with and without "
            "the twins' frames, are below. "
            if result.get("pixels")
            else "its per-pixel columns cannot be recomputed from the committed evaluation "
            "files, which pool the frames (no per-scene or per-frame counts). "
        )
        + f"`{SUITE}` keeps {sum(su['kept_classes'].values())} of its {su['scenes']} findings ({kept}); "
        "its pass counts, from the outcomes recorded per scenario:",
        "",
        f"| arm | {SUITE} passed, as committed | of them twins | {SUITE} passed, twins left out |",
        "|---|---|---|---|",
    ]
    for arm in _arms(result):
        (k, n), (k2, n2) = su["passed"][arm], su["passed_without"][arm]
        lines.append(f"| {arm} | {k} / {n} | {k - k2} / {n - n2} | {k2} / {n2} |")
    px = result.get("pixels")
    if px:
        c, a, w = px["committed"], px[RERENDERED], px[LEFT_OUT]
        lines += [
            "",
            f"`{SET}`, per pixel: as committed ({c['frames']} frames), rendered again as built "
            f"({a['frames']} frames, {'the same scenes, frame count, seed and perturbations' if px['same_set'] else 'NOT the same set'}) "
            f"and without the twins' frames ({w['frames']}; `bash scripts/repro/heldout_twins.sh`):",
            "",
            "| arm | obstacle IoU: committed / again / twins left out | shadow false-obstacle: committed / again / twins left out |",
            "|---|---|---|",
        ]
        for arm in _arms(result):
            if arm not in c["arms"]:
                continue
            cells = [" / ".join(f"{x['arms'][arm][i]:.3f}" for x in (c, a, w)) for i in (0, 1)]
            lines.append(f"| {arm} | {cells[0]} | {cells[1]} |")
    lines += [
        "",
        f"Rebuild at the radius: `{REBUILD}`, then round 2's `harden.sh runs/harden 2` (section 4); "
        "`--apart-from` now checks at this radius by default and drops the twins.",
    ]
    return "\n".join(lines)


def block(result: dict) -> str:
    return f"{BEGIN}\n{markdown(result)}\n{END}"


def in_doc(doc: str) -> str:
    """The page's block as it stands ('' if it has none)."""
    with open(doc, encoding="utf-8") as f:
        m = re.search(re.escape(BEGIN) + r".*?" + re.escape(END), f.read(), re.S)
    return m.group(0) if m else ""


def write_doc(doc: str, text: str) -> None:
    """Writes `text` (markers included) as the page's twins block (asg_analysis.docblocks)."""
    from asg_analysis.docblocks import rewrite_between

    if rewrite_between(doc, BEGIN, END, text, False, PROG) == 2:
        raise ValueError(f"{doc}: no {BEGIN} ... {END} block to fill")


def run(argv=None) -> int:
    ap = argparse.ArgumentParser(prog=PROG, description=__doc__.split("\n\n")[0])
    ap.add_argument("folder", nargs="?", default=HARD, help="results/hardening")
    ap.add_argument("--tol-m", type=float, default=None, help="[m] (default: overlap's, the augmentation's radius)")
    ap.add_argument("--doc", help="a Markdown file whose twins block to rewrite")
    ap.add_argument("--check", action="store_true", help="with --doc: exit 1 if its block is not in step")
    ap.add_argument("--json", help="write the figures here")
    ap.add_argument(
        "--frames-without-twins", nargs=2, metavar=("FRAMES", "OUT"), help="write a dataset of FRAMES without the twins"
    )
    a = ap.parse_args(argv)
    try:
        if a.frames_without_twins:
            n = without_twins(*a.frames_without_twins, folder=a.folder)
            print(f"{a.frames_without_twins[1]}: the frames of {a.frames_without_twins[0]} but {n} of the twins'")
            return 0
        result = measure(a.folder, a.tol_m)
        text = block(result)
        if a.json:
            with open(a.json, "w", encoding="utf-8") as f:
                json.dump(result, f, indent=1)
        if a.doc and a.check:
            if in_doc(a.doc) != text:
                print(f"{a.doc}: the twins block is not in step; rewrite it with --doc", file=sys.stderr)
                return 1
        elif a.doc:
            write_doc(a.doc, text)
        print(markdown(result))
    except (OSError, ValueError, KeyError) as e:
        print(f"held_apart: {e}", file=sys.stderr)
        return 2
    return 0
