"""Training frames from scenes (issue #40; docs/design-loop.md, "Harden"): camera poses along the
trajectories a campaign stored, in the scene itself and in perturbed copies of it (the sun moved,
the obstacles shifted), rendered with the simulator's ground-truth labels by
`asg_sim_dataset --poses`. The same recipe serves both arms of the hardening study: the scenes of
a suite's findings, and as many scenes drawn from a random campaign, so the two frame sets differ
only in where their scenes came from. No ROS; the renderer is a subprocess.

A frame set is a folder:

- `hardening.json`: where every scene came from, the settings, the seed and the frame count;
- `scenarios/NNN-NAME-vK.yaml`: the scenes rendered (K = 0: the scene as it ran; K >= 1 perturbed),
  each a scenario file that `replay --scenario` or `asg_sim_render` opens;
- `poses.csv`: scenario, x [m], y [m], yaw [rad] per frame;
- `frames/`: the dataset (manifest.csv, images/) that `train_unet --data` reads.

The same sources, settings and seed give the same files.
"""

import json
import math
import os
import subprocess
from dataclasses import asdict, dataclass, field
from typing import List, Optional, Sequence

import numpy as np

from asg_agent.campaign.overlap import AUGMENT_SHIFT_M


def dataset_tool() -> str:
    """asg_sim's `asg_sim_dataset`, found as ROS finds executables (asg_scenario.binaries; an
    exec_depend of asg_agent)."""
    from asg_scenario.binaries import BinaryNotFound, find_binary

    try:
        return find_binary("asg_sim", "asg_sim_dataset")
    except BinaryNotFound as e:
        raise HardeningError(str(e)) from None


FORMAT = "asg_hardening/1"


class HardeningError(ValueError):
    """Unusable input for a frame set: the message names the file or the value."""


@dataclass
class Perturbation:
    """How frames spread around a stored run (every value a largest change, drawn uniformly)."""

    variants: int = 4  #: [-] scenes per source: the scene as it ran and variants - 1 perturbed copies
    sun_inclination_deg: float = 10.0  #: [deg] change of the sun's elevation (kept within 0..90)
    sun_yaw_deg: float = 30.0  #: [deg] change of the direction the light comes from
    shift_m: float = AUGMENT_SHIFT_M  #: [m] shift of every obstacle along x and along y (overlap.py)
    lateral_m: float = 1.0  #: [m] sideways offset of a camera pose from the trajectory
    heading_rad: float = 0.15  #: [rad] change of a pose's heading from the trajectory's
    approach_m: float = 25.0  #: [m] last stretch of the run (a failure's approach) that gets half the poses
    clearance_m: float = 0.5  #: [m] least gap between the camera and an obstacle's collision cylinder

    def check(self):
        if self.variants < 1:
            raise HardeningError(f"variants must be >= 1 (got {self.variants})")
        for k in ("sun_inclination_deg", "sun_yaw_deg", "shift_m", "lateral_m", "heading_rad", "approach_m"):
            v = getattr(self, k)
            if not (math.isfinite(v) and v >= 0):
                raise HardeningError(f"{k} must be a finite number >= 0 (got {v})")


CAMERA_AHEAD_M = 1.5  # [m] the camera mount's forward offset (asg_sim_dataset, cameraMount(1.5, 0, 1.4))


@dataclass
class Source:
    """A scene and the run stored for it."""

    name: str  #: file-name-safe, unique in a frame set
    request: dict  #: the validated scenario
    trajectory: np.ndarray  #: N x 2 [m], the vehicle's positions (10 Hz)
    origin: dict = field(default_factory=dict)  #: campaign, job, attribution, termination, collision


def _rows_by_job(path: str):
    from asg_agent.records.export import read_export

    camp, rows = read_export(path)
    return camp, {int(r["job"]): r for r in rows}


def _source(camp: dict, row: dict, name: str, request: Optional[dict] = None) -> Source:
    from asg_scenario import validate_scenario

    from asg_agent.records.scenes import scenario_of

    xy = np.asarray(row.get("trajectory_xy") or [], dtype=np.float64).reshape(-1, 2)
    if len(xy) < 2:
        raise HardeningError(f"{camp['name']} job {row['job']}: the export stores no trajectory")
    req = request if request is not None else validate_scenario(scenario_of(camp, row), name)
    origin = {
        "campaign": camp["name"],
        "job": int(row["job"]),
        "attribution": row.get("attribution"),
        "termination": row.get("termination"),
        "collision_with": row.get("collision_with"),
    }
    return Source(name, req, xy, origin)


def sources_from_suite(folder: str, export_dirs: Sequence[str]) -> List[Source]:
    """The findings of a suite, each with the trajectory its campaign's export stored (an export
    `CAMPAIGN.jsonl.gz` in one of `export_dirs`)."""
    from asg_agent.campaign.suite import load_suite

    suite = load_suite(folder)
    exports, out = {}, []
    for e in suite["scenarios"]:
        camp = e["campaign"]
        if camp not in exports:
            paths = [os.path.join(d, camp + ".jsonl.gz") for d in export_dirs]
            found = [p for p in paths if os.path.isfile(p)]
            if not found:
                raise HardeningError(f"{folder}: no export of campaign {camp} in {', '.join(export_dirs)}")
            exports[camp] = _rows_by_job(found[0])
        c, rows = exports[camp]
        if int(e["job"]) not in rows:
            raise HardeningError(f"{found[0]}: no job {e['job']} (suite {folder}, {e['file']})")
        name = os.path.splitext(os.path.basename(e["file"]))[0]
        out.append(_source(c, rows[int(e["job"])], name, e["request"]))
    return out


def sources_from_export(path: str, count: int = 0, seed: int = 0, classes: Sequence[str] = ()) -> List[Source]:
    """Scenes of a campaign export: those of the attribution `classes` (every one when `count` is
    0), or `count` of them, or of all its scenes when no class is named, drawn without replacement
    (seeded) whatever their outcome: the control arm's scenes when the export is a random
    campaign's."""
    camp, rows = _rows_by_job(path)
    jobs = sorted(j for j, r in rows.items() if not classes or r.get("attribution") in classes)
    what = f"scenes of class {', '.join(classes)}" if classes else "scenes"
    if not jobs or count > len(jobs):
        raise HardeningError(f"{path}: {count or 'some'} {what} asked, {len(jobs)} stored")
    if count <= 0:
        count = len(jobs)
    pick = sorted(np.random.default_rng(seed).choice(len(jobs), size=count, replace=False))
    return [_source(camp, rows[jobs[i]], f"{k:03d}-{camp['name']}-job{jobs[i]}") for k, i in enumerate(pick)]


def perturbed(request: dict, rng: np.random.Generator, p: Perturbation, name: str) -> dict:
    """A copy of `request` with the sun moved and every obstacle shifted (validated; a draw the
    validator rejects is drawn again, up to 20 times)."""
    import copy

    from asg_scenario import ScenarioError, validate_scenario

    last = None
    for _ in range(20):
        s = copy.deepcopy(request)
        s["name"] = name
        t = s["textural"]
        t["sun_inclination_deg"] = float(
            np.clip(t["sun_inclination_deg"] + rng.uniform(-p.sun_inclination_deg, p.sun_inclination_deg), 0.0, 90.0)
        )
        t["sun_yaw_deg"] = float(
            (t["sun_yaw_deg"] + rng.uniform(-p.sun_yaw_deg, p.sun_yaw_deg) + 180.0) % 360.0 - 180.0
        )
        size = s["structural"]["landscape"]["size"]
        for layout in s["structural"]["layouts"]:
            for inst in layout["instances"]:
                inst["x"] = float(np.clip(inst["x"] + rng.uniform(-p.shift_m, p.shift_m), 0.0, size))
                inst["y"] = float(np.clip(inst["y"] + rng.uniform(-p.shift_m, p.shift_m), 0.0, size))
        try:
            return validate_scenario(s, name)
        except ScenarioError as e:
            last = e
    raise HardeningError(f"{name}: no valid perturbation in 20 draws ({last})")


def obstacles(request: dict) -> np.ndarray:
    """M x 3: x [m], y [m], collision radius [m] of every visible instance."""
    from asg_scenario.catalogue import MESHES

    out = [
        (inst["x"], inst["y"], MESHES[layout["mesh_name"]].collision_radius * inst["scale"])
        for layout in request["structural"]["layouts"]
        if layout["mesh_name"] in MESHES
        for inst in layout["instances"]
        if inst.get("visible", True)
    ]
    return np.asarray(out, dtype=np.float64).reshape(-1, 3)


def arc_length(xy: np.ndarray) -> np.ndarray:
    return np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(xy, axis=0), axis=1))])


def poses_along(xy: np.ndarray, n: int, rng: np.random.Generator, p: Perturbation, obs: np.ndarray) -> List[tuple]:
    """`n` camera poses (x [m], y [m], yaw [rad]) near the trajectory `xy`: half at arc lengths
    drawn over the whole run, half over its last `approach_m`, each moved sideways and turned
    by the perturbation's bounds, the camera kept `clearance_m` clear of every obstacle (an
    approach pose with no clear draw in 50 is drawn over the whole run). Raises HardeningError
    when no clear pose is found in 100 draws."""
    s = arc_length(xy)
    total = s[-1]
    out = []
    for k in range(n):
        for attempt in range(100):
            lo = max(0.0, total - p.approach_m) if k % 2 == 1 and attempt < 50 else 0.0
            at = rng.uniform(lo, total) if total > 0 else 0.0
            i = int(np.searchsorted(s, at, side="right") - 1)
            i = min(max(i, 0), len(xy) - 2)
            f = (at - s[i]) / (s[i + 1] - s[i]) if s[i + 1] > s[i] else 0.0
            point = xy[i] + f * (xy[i + 1] - xy[i])
            ahead = np.searchsorted(s, at + 1.0)  # heading over the next metre (or the last one)
            j = min(int(ahead), len(xy) - 1)
            d = xy[j] - point if np.linalg.norm(xy[j] - point) > 1e-3 else point - xy[max(0, i - 10)]
            heading = math.atan2(d[1], d[0]) if np.linalg.norm(d) > 1e-3 else 0.0
            side = rng.uniform(-p.lateral_m, p.lateral_m)
            yaw = heading + rng.uniform(-p.heading_rad, p.heading_rad)
            x = point[0] - side * math.sin(heading)
            y = point[1] + side * math.cos(heading)
            cam = np.array([x + CAMERA_AHEAD_M * math.cos(yaw), y + CAMERA_AHEAD_M * math.sin(yaw)])
            if not len(obs) or np.all(np.hypot(*(obs[:, :2] - cam).T) > obs[:, 2] + p.clearance_m):
                break
        else:
            raise HardeningError(f"no camera pose {p.clearance_m} m clear of the obstacles in 100 draws")
        out.append((float(x), float(y), float((yaw + math.pi) % (2 * math.pi) - math.pi)))
    return out


def write_frame_set(sources: List[Source], out: str, frames: int, seed: int, p: Perturbation, made_from: dict) -> dict:
    """Writes `out`/scenarios, poses.csv and hardening.json for `frames` frames spread evenly over
    the sources and their variants (the first sources take the remainder). Returns the metadata."""
    from asg_scenario import dump_scenario

    p.check()
    if not sources:
        raise HardeningError("no scenes to make frames of")
    if frames < len(sources) * p.variants:
        raise HardeningError(f"{frames} frames are fewer than {len(sources)} scenes x {p.variants} variants")
    os.makedirs(os.path.join(out, "scenarios"), exist_ok=True)
    rows, meta = [], []
    per, extra = divmod(frames, len(sources))
    for k, src in enumerate(sources):
        rng = np.random.default_rng([seed, k])
        n_src = per + (1 if k < extra else 0)
        counts = [n_src // p.variants + (1 if v < n_src % p.variants else 0) for v in range(p.variants)]
        files = []
        for v, n in enumerate(counts):
            name = f"{src.name}-v{v}"
            req = dict(src.request, name=name) if v == 0 else perturbed(src.request, rng, p, name)
            fname = f"scenarios/{name}.yaml"
            with open(os.path.join(out, fname), "w", encoding="utf-8") as f:
                how = "as it ran" if v == 0 else "perturbed (issue #40 hardening)"
                f.write(f"# {src.origin.get('campaign')} job {src.origin.get('job')}, {how}\n")
                f.write(dump_scenario(req))
            rows += [(fname, *pose) for pose in poses_along(src.trajectory, n, rng, p, obstacles(req))]
            files.append(fname)
        meta.append({"name": src.name, **src.origin, "frames": n_src, "scenarios": files})
    with open(os.path.join(out, "poses.csv"), "w", encoding="utf-8") as f:
        f.write("scenario,x,y,yaw\n")
        f.writelines(f"{r[0]},{r[1]:.4f},{r[2]:.4f},{r[3]:.5f}\n" for r in rows)
    info = {
        "format": FORMAT,
        "made_from": made_from,
        "seed": seed,
        "frames": len(rows),
        "perturbation": asdict(p),
        "sources": meta,
    }
    with open(os.path.join(out, "hardening.json"), "w", encoding="utf-8") as f:
        json.dump(info, f, indent=1)
    return info


def render(out: str, tool: str = "", quiet: bool = False) -> str:
    """Renders `out`/poses.csv into `out`/frames with asg_sim_dataset (or `tool`); returns that folder."""
    tool = tool or dataset_tool()
    if not os.path.isfile(tool):
        raise HardeningError(f"{tool}: not built (build the workspace: scripts/common.sh build_workspace)")
    frames = os.path.join(out, "frames")
    env = dict(os.environ, LP_NUM_THREADS=os.environ.get("LP_NUM_THREADS", "1"))
    r = subprocess.run(
        [tool, "--out", frames, "--poses", os.path.join(out, "poses.csv")],
        env=env,
        stderr=subprocess.PIPE if quiet else None,
        text=True,
    )
    if r.returncode != 0:
        raise HardeningError(f"asg_sim_dataset failed ({r.returncode}): {(r.stderr or '').strip()[-500:]}")
    return frames
