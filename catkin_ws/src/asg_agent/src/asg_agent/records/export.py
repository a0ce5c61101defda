"""A campaign's compact export (gzip JSON lines, a few hundred bytes a scenario; results/ keeps
them): writing one from a store, reading it back, its counts, and which obstacle a run hit. No ROS.
The command line is asg_agent.cli.store; figures and tables over exports are asg_analysis's."""

import io
import json
from typing import Optional

import numpy as np

from asg_agent.records.store import DIFFERENTIAL, Store, attribute, unpack_trajectory
from asg_agent.scoring.attribution import FINDING, FINDING_STRONG, count_classes


def collision_index(request: dict, collision_with: str) -> Optional[int]:
    """The store's "layout:instance" of the obstacle a run collided with, as an index into the
    export's flat `positions` / `meshes` lists; None when the run hit nothing (or an old row)."""
    if not collision_with:
        return None
    try:
        layout, instance = (int(v) for v in collision_with.split(":"))
    except ValueError:
        raise ValueError(f"collision_with {collision_with!r} is not 'layout:instance'") from None
    layouts = request["structural"]["layouts"]
    if not (0 <= layout < len(layouts) and 0 <= instance < len(layouts[layout]["instances"])):
        raise ValueError(f"collision_with {collision_with!r} names no obstacle of the request")
    return sum(len(l["instances"]) for l in layouts[:layout]) + instance


#: the campaign settings that hold a file's path
PATH_SETTINGS = ("experiment_file", "stack_file")


def committed_paths(campaign: dict) -> dict:
    """The campaign row with the paths its settings hold (PATH_SETTINGS) made repository-relative,
    as results/ keeps them (issue #68: an export holds no machine's paths): a store written before
    stored them absolute. A path of another checkout falls back to the recorded
    `experiment_repo_file`; a file outside any repository keeps its absolute path. Settings
    without an absolute path are left as stored, byte for byte."""
    import os

    from asg_agent.paths import repo_relative

    if not isinstance(campaign.get("settings"), str) or not campaign["settings"]:
        return campaign
    settings = json.loads(campaign["settings"])
    changed = False
    for key in PATH_SETTINGS:
        path = settings.get(key)
        if isinstance(path, str) and os.path.isabs(path):
            rel = repo_relative(path) or (settings.get("experiment_repo_file", "") if key == "experiment_file" else "")
            if rel:
                settings[key] = rel
                changed = True
    # the store's own formatting (records.store: sorted keys)
    return dict(campaign, settings=json.dumps(settings, sort_keys=True)) if changed else campaign


def export(store: Store, campaign: str, out: str, hz: float = 10.0) -> int:
    """A compact export of a campaign (gzip JSON lines, a few hundred bytes a scenario): the
    campaign row first, then per scenario its job, episode, step, obstacle positions, every proxy
    term, termination, the obstacle hit (`collision_with`, an index into `positions`) and the
    trajectory at `hz` (x, y to 1 cm); the settings' paths repository-relative (committed_paths).
    Enough to recompute every count
    and draw every figure without the store; the store keeps the full requests and 60 Hz
    trajectories for exact replays."""
    import gzip

    c = store.campaign(campaign)
    if c is None:
        raise ValueError(f"no campaign {campaign!r} in {store.path}")
    n = 0
    # mtime 0 and no file name in the gzip header: the same campaign exports to the same bytes.
    with (
        open(out, "wb") as raw,
        gzip.GzipFile(filename="", mode="wb", fileobj=raw, mtime=0) as gz,
        io.TextIOWrapper(gz, encoding="utf-8") as f,
    ):
        f.write(json.dumps({"campaign": committed_paths(c)}) + "\n")
        for r in store.rows(campaign):
            req = json.loads(r["request"])
            traj = unpack_trajectory(r["trajectory"])
            step = max(1, int(round(60.0 / hz)))
            keep = np.r_[traj[::step], traj[-1:]]
            f.write(
                json.dumps(
                    {
                        "job": r["job"],
                        "episode": r["episode"],
                        "step": r["step"],
                        "worker": r["worker"],
                        "scenario_id": r["scenario_id"],
                        "termination": r["termination"],
                        "error": r["error"],
                        "proxy": r["proxy"],
                        "vis": r["vis"],
                        "yaw_term": r["yaw_term"],
                        "plr": r["plr"],
                        "path_length": r["path_length"],
                        "optimal_length": r["optimal_length"],
                        "sim_time": r["sim_time"],
                        "positions": [
                            [round(i["x"], 3), round(i["y"], 3)]
                            for l in req["structural"]["layouts"]
                            for i in l["instances"]
                        ],
                        "meshes": [l["mesh_name"] for l in req["structural"]["layouts"] for _ in l["instances"]],
                        # the obstacle the run collided with: an index into positions and meshes
                        "collision_with": collision_index(req, r["collision_with"]),
                        "textural": req["textural"],
                        # issue #27: the ground's shape (absent: the flat ground)
                        **({"terrain": req["structural"]["terrain"]} if req["structural"].get("terrain") else {}),
                        "visibility": json.loads(r["visibility"]),
                        "wall_time": round(r["wall_time"], 3),
                        "removed": json.loads(r["removed"]),
                        "finished": round(r["finished"], 2),
                        "attempts": r["attempts"],
                        "reward": r["reward"],
                        "reference": json.loads(r["reference"]) if r["reference"] else None,
                        # issue #36: named reference stacks ({role: run}) and the class
                        **(
                            {"attribution": r["attribution"]}
                            | ({"reference_runs": json.loads(r["reference_runs"])} if r["reference_runs"] else {})
                            if r["attribution"]
                            else {}
                        ),
                        "trajectory_xy": np.round(keep[:, 1:3], 2).tolist(),
                    }
                )
                + "\n"
            )
            n += 1
    return n


def read_export(path: str):
    """(campaign, rows) of an export. orjson parses it (scripts/common.sh pins it): the same
    values as json.loads, numbers included (test_campaign_outputs.py compares them), in less
    than half the time."""
    import gzip

    import orjson

    with gzip.open(path, "rb") as f:
        head = orjson.loads(f.readline())
        rows = [orjson.loads(line) for line in f]
    return head["campaign"], rows


def counts(rows) -> dict:
    """Counts of an export; with attribution (rows carrying the reference stack's run) also the
    findings that are the perception's (proxy >= 3, reference < 2), the stack's (both >= 3), the
    differential ones (proxy - reference >= 1), and the collisions that are the perception's
    (the reference drove through) or the stack's (both collided), as the store's summary counts them."""
    p = [r["proxy"] for r in rows if r["proxy"] is not None]
    out = {
        "scenarios": len(rows),
        "proxy_ge_3": sum(v >= FINDING for v in p),
        "proxy_ge_4": sum(v >= FINDING_STRONG for v in p),
        "max_proxy": max(p) if p else None,
        "terminations": {t: sum(r["termination"] == t for r in rows) for t in sorted({r["termination"] for r in rows})},
    }
    pairs = [
        (r["proxy"], r["reference"]["proxy"])
        for r in rows
        if r["proxy"] is not None and r.get("reference") and r["reference"].get("proxy") is not None
    ]
    if pairs:
        kinds = [attribute(t, ref) for t, ref in pairs]
        out.update(
            attributed=len(pairs),
            perception_ge3=sum(k[1] for k in kinds),
            stack_ge3=sum(k[2] for k in kinds),
            differential_ge1=sum(t - ref >= DIFFERENTIAL for t, ref in pairs),
        )
    refs = [(r["termination"], r["reference"].get("termination")) for r in rows if r.get("reference")]
    if refs:
        out.update(
            perception_collisions=sum(t == "COLLISION" and ref == "SUCCESS" for t, ref in refs),
            stack_collisions=sum(t == "COLLISION" and ref == "COLLISION" for t, ref in refs),
        )
    labels = [r["attribution"] for r in rows if r.get("attribution")]
    if labels:
        out["classes"] = count_classes(labels)
    return out
