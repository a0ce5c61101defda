"""Regression suites (issue #40; no ROS): a campaign's distinct findings as scenario files with
their outcomes per stack, run against any stack, pass or fail per scenario, JUnit XML and JSON.

A suite is a folder a user can commit:

    SUITE/suite.yaml                 format_version, where it came from, the failure bound, and per
                                     scenario: its file, campaign, job, seed, class, failure mode,
                                     the stack it failed on, its outcome on every stack it ran on
                                     (keyed by a label), and the replay command
    SUITE/scenarios/NNN-NAME.yaml    each a scenario file (docs/scenario-format.md)

`export_suite` picks, from campaign exports, one finding per failure mode (records/failure_modes.py)
of the chosen attribution classes. `load_suite` refuses a suite of another format version, or a
scenario the current validator rejects, naming the file and the problem. `run_suite` runs every
scenario on a pool of workers (any stack) and gives each a verdict: it *fails* when it ends in a
collision, a timeout, a flip or out of bounds, or reaches the goal with proxy >= the suite's bound
(scoring/attribution.py's rule); against a recorded label it is a *regression* when it passed
there and fails now, *fixed* the other way. `record` stores a run's outcomes under a label (with
a digest of the trajectory, so that a second run of the same stack can be checked identical).
"""

import hashlib
import json
import os
import time
from typing import Dict, List, Optional, Sequence
from xml.etree import ElementTree as ET

import numpy as np
import yaml

from asg_agent.campaign.dispatch import Outcome, Pool, run_each
from asg_agent.records.store import kept_xy
from asg_agent.scoring import attribution as attr
from asg_agent.scoring.proxy import run_terms

FORMAT_VERSION = 1
MAX_ATTEMPTS = 3  # runs of a scenario before its ERROR stands


class SuiteError(ValueError):
    pass


class _Dumper(yaml.SafeDumper):
    """Plain YAML: every entry written out, no anchors (a suite is read by people too)."""

    def ignore_aliases(self, data):
        return True


def digest(trajectory) -> str:
    """sha256 of the float32 trajectory (t, x, y, yaw, yaw rate): identical runs, identical digests."""
    return hashlib.sha256(np.ascontiguousarray(np.asarray(trajectory, np.float32)).tobytes()).hexdigest()[:16]


def verdict(termination: str, proxy: Optional[float], bound: float) -> tuple:
    """(fails, reason) of one run under the suite's bound [-] on the proxy."""
    if termination == "ERROR" or proxy is None:
        return True, f"no outcome ({termination})"
    if termination in attr.FAILED_TERMINATIONS:
        return True, termination.lower().replace("_", " ")
    if proxy >= bound:
        return True, f"proxy {proxy:.2f} >= {bound:g}"
    return False, f"reached the goal, proxy {proxy:.2f}"


def export_suite(
    exports: List[str],
    out: str,
    classes=("flaw",),
    limit: int = 0,
    label: str = "",
    apart_from: Sequence[str] = (),
    drop_shared: bool = False,
) -> dict:
    """Writes the suite folder `out` from campaign exports: one finding per failure mode of the
    attribution `classes` (earliest job first), at most `limit` (0: all). `label` names the stack
    the campaign ran, for its recorded outcomes (default: its model and backend). `apart_from`:
    training sources (exports, suites, frame sets; campaign.overlap) whose scenes the suite must
    not hold: a shared finding is refused (OverlapError naming them all), or with `drop_shared`
    left out (the next finding of its mode may take its place), and listed in `dropped_shared`."""
    from asg_scenario import dump_scenario, validate_scenario

    from asg_agent.records import failure_modes as fm
    from asg_agent.records.scenes import scenario_of
    from asg_agent.records.export import read_export

    from asg_agent.campaign import overlap

    training = [sc for src in apart_from for sc in overlap.scenes_of(src)]
    shared_pairs, dropped = [], []
    os.makedirs(os.path.join(out, "scenarios"), exist_ok=True)
    entries, seen = [], set()
    for path in exports:
        camp, rows = read_export(path)
        settings = json.loads(camp["settings"]) if isinstance(camp["settings"], str) else camp["settings"]
        stack = {k: settings.get(k) for k in ("perception", "model", "unet_backend", "planner_config", "numerics")}
        test_label = label or f"{settings.get('model')}-{settings.get('unet_backend')}"
        for r in sorted(rows, key=lambda r: r["job"]):
            if r.get("attribution") not in classes:
                continue
            req = scenario_of(camp, r)
            mode = fm.mode(r, req)
            if mode in seen:
                continue
            if training:
                pairs = overlap.shared([overlap.request_scene(f"{camp['name']} job {r['job']}", req)], training)
                if pairs:
                    (dropped if drop_shared else shared_pairs).extend(pairs)
                    continue
            seen.add(mode)
            req["name"] = f"{camp['name']}-job{r['job']}"
            req = validate_scenario(req, req["name"])
            name = f"{len(entries):03d}-{camp['name']}-job{r['job']}.yaml"
            with open(os.path.join(out, "scenarios", name), "w", encoding="utf-8") as f:
                f.write(
                    f"# {r['attribution']} finding of campaign {camp['name']} (job {r['job']}, seed {camp['seed']})\n"
                )
                f.write(dump_scenario(req))
            outcomes = {test_label: {"termination": r["termination"], "proxy": r["proxy"]}}
            for role, run in (r.get("reference_runs") or {}).items():
                outcomes[role] = {"termination": run["termination"], "proxy": run["proxy"]}
            entries.append(
                {
                    "file": f"scenarios/{name}",
                    "campaign": camp["name"],
                    "job": r["job"],
                    "seed": camp["seed"],
                    "class": r["attribution"],
                    "mode": fm.label(mode),
                    "failed_on": stack,
                    "outcomes": outcomes,
                    "replay": f"rosrun asg_agent replay --scenario scenarios/{name} --perception "
                    f"{stack['perception']} --model {stack['model']}",
                }
            )
            if limit and len(entries) >= limit:
                break
        if limit and len(entries) >= limit:
            break
    if shared_pairs:
        listed = "; ".join(f"{p['scene']} = {p['training']}" for p in shared_pairs)
        raise overlap.OverlapError(
            f"suite {out}: findings held in a training source: {listed} (--drop-shared leaves them out)"
        )
    suite = {
        "format_version": FORMAT_VERSION,
        "made_from": [os.path.basename(p) for p in exports],
        **({"apart_from": [os.path.basename(p.rstrip("/")) for p in apart_from]} if apart_from else {}),
        **({"dropped_shared": [f"{p['scene']} = {p['training']}" for p in dropped]} if dropped else {}),
        "classes": list(classes),
        "bound": attr.FINDING,
        "scenarios": entries,
    }
    with open(os.path.join(out, "suite.yaml"), "w", encoding="utf-8") as f:
        yaml.dump(suite, f, Dumper=_Dumper, sort_keys=False)
    return suite


def load_suite(folder: str) -> dict:
    """The suite of `folder` with every scenario loaded and validated (key `request`)."""
    from asg_scenario import ScenarioError, load_scenario

    path = os.path.join(folder, "suite.yaml")
    try:
        with open(path, encoding="utf-8") as f:
            suite = yaml.safe_load(f)
    except (OSError, yaml.YAMLError) as e:
        raise SuiteError(f"{path}: not a readable suite ({e})") from None
    if not isinstance(suite, dict) or suite.get("format_version") != FORMAT_VERSION:
        got = suite.get("format_version") if isinstance(suite, dict) else None
        raise SuiteError(f"{path}: format_version {got!r}, this tool reads {FORMAT_VERSION}")
    if not isinstance(suite.get("scenarios"), list) or not suite["scenarios"]:
        raise SuiteError(f"{path}: no scenarios")
    for k, e in enumerate(suite["scenarios"]):
        if not isinstance(e, dict) or "file" not in e:
            raise SuiteError(f"{path}: scenario {k} names no file")
        try:
            e["request"] = load_scenario(os.path.join(folder, e["file"]))
        except ScenarioError as err:
            raise SuiteError(f"{path}: scenario {k} ({e['file']}) is rejected by the validator: {err}") from None
    suite["_folder"] = folder
    return suite


def run_suite(suite: dict, pool: Pool, poll: float = 0.2, progress=None) -> List[dict]:
    """Runs every scenario of the suite on `pool`; one result per scenario, in the suite's order."""
    todo = list(range(len(suite["scenarios"])))
    done: Dict[int, Outcome] = {}

    def keep(k, o):
        done[k] = o
        if progress:
            progress(len(done), len(todo))

    requests = [dict(e["request"], scenario_id=9000 + k) for k, e in enumerate(suite["scenarios"])]
    run_each(pool, requests, keep, poll, MAX_ATTEMPTS)
    out = []
    for k in todo:
        e, o = suite["scenarios"][k], done[k]
        _, terms = run_terms(e["request"], o)
        proxy = terms.proxy if terms else None
        fails, reason = verdict(o.termination, proxy, suite.get("bound", attr.FINDING))
        if o.termination == "COLLISION" and o.collision_with:
            reason += f" ({o.collision_with})"
        out.append(
            {
                "file": e["file"],
                "termination": o.termination,
                "proxy": proxy,
                "fails": fails,
                "reason": reason,
                "digest": digest(o.trajectory),
                "sim_time": o.sim_time,
                "wall_time": o.wall_time,
                # the path driven as a campaign keeps a reference run's (loop.kept_xy), for figures
                "trajectory_xy": kept_xy(o.trajectory),
            }
        )
    return out


def compare(suite: dict, results: List[dict], against: str = "", numerics: str = "") -> List[dict]:
    """Adds to each result its recorded outcome under `against` and the change: 'regression'
    (passed there, fails now), 'fixed', 'same'; 'changed' when it passes or fails alike but the
    trajectory differs from a recorded digest; 'new' without a record. A digest is compared only
    where the segmenter's `numerics` here can repeat the recorded ones (asg_perception.numerics,
    issue #36): on another CPU's kernels only pass and fail are, and the result says why."""
    bound = suite.get("bound", attr.FINDING)
    for e, r in zip(suite["scenarios"], results):
        rec = (e.get("outcomes") or {}).get(against) if against else None
        if rec is None:
            r["change"] = "new"
            continue
        was, _ = verdict(rec["termination"], rec.get("proxy"), bound)
        r["recorded"] = rec
        if was and not r["fails"]:
            r["change"] = "fixed"
        elif r["fails"] and not was:
            r["change"] = "regression"
        elif rec.get("digest") and rec["digest"] != r["digest"] and not _other_numerics(rec, numerics, r):
            r["change"] = "changed"
        else:
            r["change"] = "same"
    return results


def _other_numerics(rec: dict, numerics: str, result: dict) -> bool:
    """True (and the result noted) when the recorded run's numerics cannot be repeated here."""
    if not rec.get("numerics") or not numerics:
        return False
    from asg_perception.numerics import can_reproduce

    why = can_reproduce(rec["numerics"], numerics)
    if why:
        result["note"] = f"trajectory not compared: {why}"
    return bool(why)


def record(suite: dict, results: List[dict], label: str, numerics: str = ""):
    """Stores `results` as the outcomes of stack `label` in the suite's file (with the segmenter's
    numerics they ran with, when it has one)."""
    folder = suite["_folder"]
    with open(os.path.join(folder, "suite.yaml"), encoding="utf-8") as f:
        raw = yaml.safe_load(f)
    for e, r in zip(raw["scenarios"], results):
        e.setdefault("outcomes", {})[label] = {
            "termination": r["termination"],
            "proxy": r["proxy"],
            "digest": r["digest"],
            **({"numerics": numerics} if numerics else {}),
        }
    tmp = os.path.join(folder, "suite.yaml.part")
    with open(tmp, "w", encoding="utf-8") as f:
        yaml.dump(raw, f, Dumper=_Dumper, sort_keys=False)
    os.replace(tmp, os.path.join(folder, "suite.yaml"))


def junit(results: List[dict], name: str, path: str, fail_on=("regression", "changed")):
    """JUnit XML: one testcase per scenario; a failure where its change is in `fail_on` (or, with
    no record to compare with, where it fails)."""
    cases = ET.Element("testsuite", name=name, tests=str(len(results)))
    failures = 0
    for r in results:
        tc = ET.SubElement(
            cases, "testcase", classname=name, name=os.path.basename(r["file"]), time=f"{r['wall_time']:.3f}"
        )
        bad = r.get("change") in fail_on or (r.get("change") == "new" and r["fails"])
        if bad:
            failures += 1
            msg = f"{'regression: ' if r.get('change') == 'regression' else ''}{r['reason']}"
            ET.SubElement(tc, "failure", message=msg).text = json.dumps(
                {k: r.get(k) for k in ("termination", "proxy", "recorded", "digest")}, default=str
            )
        ET.SubElement(tc, "system-out").text = f"{r['termination']} proxy {r['proxy']} ({r.get('change')})"
    cases.set("failures", str(failures))
    cases.set("timestamp", time.strftime("%Y-%m-%dT%H:%M:%S"))
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    ET.ElementTree(cases).write(path, encoding="utf-8", xml_declaration=True)
    return failures
