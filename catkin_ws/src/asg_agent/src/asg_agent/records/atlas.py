"""A failure atlas's file, built from campaign exports (no ROS imports): which exports share an
identity (scene, stack under test, references, kind of finding), the atlas of their findings, its
growth curve and completeness (scoring/atlas.py), and a new version with a campaign's new places.

The file (`scoring.atlas.FORMAT`, JSON with sorted keys) holds everything it was built from but
the rows themselves: its identity, its sources (export path, scenarios, findings, a digest of
the rows), every finding's place (class, x, y [m], source, row), the groupings at RADIUS_M and
FINE_RADIUS_M, the growth curve and Chao1 at each radius, and its version. So `add` regroups the
old findings with the new ones without the old exports, and a reader needs only the file.
"""

import glob
import hashlib
import json
import os
from typing import List, Optional, Sequence

import numpy as np

from asg_agent.records.export import read_export
from asg_agent.scoring import atlas as sa
from asg_agent.scoring.places import place_of_row

#: the keys of a reference stack's settings that decide what it does (the workers and the CPU's
#: numerics string are where and how fast it ran, not what it is)
REFERENCE_KEYS = ("perception", "model", "unet_backend", "stack", "stack_file")
GROWTH_POINTS = 60  # points of the stored growth curve
GROWTH_SEED = 0  # the shuffle of the pooled scenarios the growth curve follows


def identity(campaign: dict, kind: str) -> dict:
    """The identity an export's findings of `kind` belong to: the scene (the experiment's
    scenario file and what its experiment lets a search change beside the obstacles), the stack
    under test, the reference stacks that class its runs, and the kind."""
    import yaml

    if kind not in sa.KINDS:
        raise ValueError(f"finding kind {kind!r} is not one of {', '.join(sa.KINDS)}")
    s = json.loads(campaign.get("settings") or "{}")
    exp = yaml.safe_load(campaign.get("experiment_text") or "") or {}
    if "scenario" not in exp:
        raise ValueError(f"campaign {campaign.get('name')!r}: its experiment names no scenario")
    home = os.path.dirname(s.get("experiment_repo_file") or s.get("experiment_file") or "experiments/x.yaml")
    refs = s.get("references") or {}
    return {
        "scene": os.path.normpath(os.path.join(home, exp["scenario"])),
        "scene_free": {k: exp[k] for k in sorted(exp) if k.endswith("_free")},
        "stack": s.get("stack") or "paper",
        "perception": s.get("perception"),
        "model": s.get("model") if s.get("perception") == "unet" else None,
        "unet_backend": s.get("unet_backend") if s.get("perception") == "unet" else None,
        "planner_config": s.get("planner_config"),
        "references": {r: {k: refs[r].get(k) for k in REFERENCE_KEYS if refs[r].get(k)} for r in sorted(refs)},
        "kind": kind,
    }


def usable(campaign: dict, kind: str) -> Optional[str]:
    """Why an export's rows cannot show findings of `kind` (None: they can)."""
    s = json.loads(campaign.get("settings") or "{}")
    roles = set(s.get("references") or {})
    if kind == "flaw" and "full" not in roles:
        return "no unflawed reference re-runs its candidates (three-stack attribution)"
    if kind == "regression" and "release" not in roles:
        return "no release reference re-runs its candidates"
    return None


def digest(rows) -> str:
    """A digest of what an export's rows are (their layouts and outcomes): two exports of the
    same runs (a campaign exported twice, or replayed on another CPU) have the same digest and
    count once."""
    h = hashlib.sha256()
    for r in rows:
        h.update(json.dumps([r["positions"], r["meshes"], r["termination"], r.get("collision_with")]).encode())
    return h.hexdigest()[:16]


def _growth(findings: List[list], sources: List[dict], atlas: sa.Atlas) -> List[list]:
    """[scenarios pooled, places covered] along a seeded shuffle (GROWTH_SEED) of every pooled
    scenario (findings: [cls, x, y, source, row])."""
    base = np.cumsum([0] + [s["scenarios"] for s in sources])
    scenarios = int(base[-1])
    order = np.random.default_rng(GROWTH_SEED).permutation(max(scenarios, 1))
    at = {}
    for f in findings:
        at.setdefault(int(order[base[f[3]] + f[4]]), []).append(f)
    cov = sa.Coverage(atlas)
    marks = sorted({int(round(v)) for v in np.linspace(0, scenarios, GROWTH_POINTS + 1)})
    out, done = [], 0
    for n in marks:
        for k in sorted(i for i in at if done <= i < n):
            for f in at[k]:
                cov.add((f[0], f[1], f[2]))
        done = n
        out.append([n, len(cov.covered)])
    return out


def build(findings: List[list], sources: List[dict], ident: dict, version: int = 1) -> dict:
    """The file's dict from pooled `findings` ([cls, x, y, source index, row index in it])."""
    scenarios = sum(s["scenarios"] for s in sources)
    places = [(f[0], f[1], f[2]) for f in findings]
    groupings = []
    for r in (sa.RADIUS_M, sa.FINE_RADIUS_M):
        ps = sa.group(places, r, [f[3] for f in findings]) if places else []
        atlas = sa.Atlas(ps, r, ident)
        groupings.append(
            {
                "radius_m": r,
                "places": ps,
                "chao1": sa.chao1(p["findings"] for p in ps),
                "chao2": sa.chao2((p["campaigns"] for p in ps), len(sources)),
                "growth": _growth(findings, sources, atlas),
                "by_class": {c: atlas.size_of(c) for c in atlas.classes()},
            }
        )
    return {
        "format": sa.FORMAT,
        "version": version,
        "identity": ident,
        "sources": sources,
        "scenarios": scenarios,
        "findings": [[f[0], round(f[1], 3), round(f[2], 3), int(f[3]), int(f[4])] for f in findings],
        "groupings": groupings,
    }


def gather(paths: Sequence[str], kind: str, ident: Optional[dict] = None, start: int = 0, skip_digests=()):
    """(findings, sources, identity, skipped) of the exports `paths`: those of another identity
    than `ident` (default: the first usable export's), those that cannot show `kind` and those
    whose rows another source already holds are skipped, each with why."""
    findings, sources, skipped = [], [], []
    seen = set(skip_digests)
    for path in paths:
        campaign, rows = read_export(path)
        why = usable(campaign, kind)
        if why is None:
            mine = identity(campaign, kind)
            if ident is None:
                ident = mine
            diff = sa.same_identity(ident, mine)
            if diff:
                why = "another identity (" + ", ".join(f"{k}: {mine.get(k)!r}" for k in diff) + ")"
        if why is None:
            d = digest(rows)
            if d in seen:
                why = "the same runs as another source"
            seen.add(d)
        if why is not None:
            skipped.append((path, why))
            continue
        src = len(sources) + start
        n = 0
        for i, r in enumerate(rows):
            if sa.is_finding(r, kind):
                c, x, y = place_of_row(r)
                findings.append([c, x, y, src, i])
                n += 1
        sources.append(
            {"export": path, "campaign": campaign["name"], "scenarios": len(rows), "findings": n, "digest": d}
        )
    return findings, sources, ident, skipped


def build_from(paths: Sequence[str], kind: str, like: Optional[str] = None):
    """(file dict, skipped) of an atlas of `kind` from the exports `paths`, of the identity of the
    export `like` (default: the first usable one's)."""
    ident = identity(read_export(like)[0], kind) if like else None
    findings, sources, ident, skipped = gather(paths, kind, ident)
    if not sources:
        raise ValueError(
            "no export can show findings of kind " + kind + ": " + "; ".join(f"{p}: {w}" for p, w in skipped)
        )
    return build(findings, sources, ident), skipped


def add(atlas_file: dict, paths: Sequence[str]):
    """(the next version, skipped): the atlas with the findings of the exports `paths` (of its
    identity) pooled in and regrouped."""
    old = atlas_file
    ident = old["identity"]
    findings = [list(f) for f in old["findings"]]
    new, sources, _, skipped = gather(
        paths, ident["kind"], ident, len(old["sources"]), {s["digest"] for s in old["sources"]}
    )
    if not sources:
        raise ValueError("no export adds to the atlas: " + "; ".join(f"{p}: {w}" for p, w in skipped))
    return build(findings + new, old["sources"] + sources, ident, old["version"] + 1), skipped


def next_version(path: str, d: dict) -> int:
    """The version a rebuilt atlas `d` takes over the file `path`: 1 for a new file (or one of
    another identity), the file's own when its places (class and position) are the same, else the
    file's + 1."""
    try:
        old = read(path)
    except ValueError:
        return 1
    if sa.same_identity(old["identity"], d["identity"]):
        return 1

    def places(f):
        return [[(p["cls"], p["x"], p["y"]) for p in g["places"]] for g in f["groupings"]]

    return int(old["version"]) + (0 if places(old) == places(d) else 1)


def matching(folder: str, ident: dict) -> List[str]:
    """The atlas files in `folder` of the identity `ident`, the newest version first."""
    out = []
    for path in sorted(glob.glob(os.path.join(folder, "*.json"))):
        try:
            d = read(path)
        except ValueError:
            continue
        if not sa.same_identity(d["identity"], ident):
            out.append((-int(d["version"]), path))
    return [p for _, p in sorted(out)]


def write(d: dict, path: str):
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    with open(path, "w", encoding="utf-8") as f:
        json.dump(d, f, sort_keys=True, separators=(",", ":"))
        f.write("\n")


def read(path: str) -> dict:
    try:
        with open(path, encoding="utf-8") as f:
            d = json.load(f)
    except (OSError, ValueError) as e:
        raise ValueError(f"atlas {path}: cannot be read ({e})") from None
    if d.get("format") != sa.FORMAT:
        raise ValueError(f"atlas {path}: format {d.get('format')!r} is not {sa.FORMAT!r}")
    return d
