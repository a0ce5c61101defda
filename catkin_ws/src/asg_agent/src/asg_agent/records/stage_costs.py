"""What a campaign's stage readings say it cost: per-scenario seconds of each node's stages, the
critical path's transport, CPU per stack (the campaign prints it at its end; the benchmark tables
of asg_analysis.bench read it). No ROS."""

import os
import platform
from typing import Dict, List, Tuple

PAPER_RATE = 625.0  # scenarios an hour: 5,000 in about 8 hours (the paper)


def machine() -> dict:
    model = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    model = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    return {"cpu": model, "cores": os.cpu_count(), "python": platform.python_version()}


def _delta(first: dict, last: dict) -> dict:
    return {
        "runs": last["runs"] - first["runs"],
        "cpu": last["cpu_seconds"] - first["cpu_seconds"],
        "seconds": {s: last["seconds"][s] - first["seconds"].get(s, 0.0) for s in last["seconds"]},
        "calls": {s: last["calls"][s] - first["calls"].get(s, 0) for s in last["calls"]},
    }


# The stack's work on the lockstep critical path: the worker's wait for a command covers it. The
# nodes' publish stages are left out: a message is on the wire before publish() returns, so the
# rest of that call overlaps the next hop.
CRITICAL = ("segmenter.decode", "segmenter.inference", "planner.votes", "planner.plan")


def transport(per: dict) -> float:
    """[s a scenario] what the worker waited for beyond the stack's own work on the critical
    path: transport, (de)serialisation and scheduling."""
    return per.get("scene_worker.wait", 0.0) - sum(per.get(k, 0.0) for k in CRITICAL)


def breakdown(
    first: Dict[Tuple[str, str], dict],
    last: Dict[Tuple[str, str], dict],
    agent: dict,
    scenarios: int,
    wall: float,
    sim_seconds: float,
    workers: int,
) -> dict:
    """Per-scenario figures from stage readings. `agent`: {"seconds", "calls", "cpu"} of the
    campaign process over the same interval."""
    if scenarios < 1 or wall <= 0:
        raise ValueError("breakdown needs at least one scenario and a positive wall time")
    nodes: Dict[str, dict] = {}
    for key, end in last.items():
        d = _delta(first.get(key, end), end)
        kind = key[1]
        acc = nodes.setdefault(kind, {"cpu": 0.0, "seconds": {}, "calls": {}})
        acc["cpu"] += d["cpu"]
        for s, x in d["seconds"].items():
            acc["seconds"][s] = acc["seconds"].get(s, 0.0) + x
            acc["calls"][s] = acc["calls"].get(s, 0) + d["calls"][s]
    nodes["agent"] = {"cpu": agent["cpu"], "seconds": dict(agent["seconds"]), "calls": dict(agent["calls"])}
    per = {f"{k}.{s}": x / scenarios for k, n in nodes.items() for s, x in n["seconds"].items()}
    cpu = {k: n["cpu"] / scenarios for k, n in nodes.items()}
    out = {
        "workers": workers,
        "scenarios": scenarios,
        "wall_s": wall,
        "rate_per_hour": scenarios / wall * 3600,
        "sim_s_per_wall_s_per_worker": sim_seconds / wall / workers,
        "sim_s_per_scenario": sim_seconds / scenarios,
        "per_scenario_s": per,
        "cpu_per_scenario_s": cpu,
        "machine": machine(),
    }
    seg = nodes.get("segmenter")
    if seg and seg["calls"].get("inference"):
        calls = seg["calls"]["inference"]
        t_inf = seg["seconds"]["inference"] / calls
        frames = calls / scenarios
        cores = min(workers, os.cpu_count() or 1)
        out.update(
            frames_per_scenario=frames,
            inference_ms_per_frame=t_inf * 1000,
            inference_bound_per_hour=cores * 3600 / (frames * t_inf),
        )
        out["fraction_of_bound"] = out["rate_per_hour"] / out["inference_bound_per_hour"]
    if "scene_worker" in nodes:
        out["transport_and_waiting_s"] = transport(per)
    out["paper_ratio"] = out["rate_per_hour"] / PAPER_RATE
    return out


def stack_costs(first: dict, last: dict, groups: Dict[str, List[str]], scenarios: int) -> dict:
    """CPU per campaign scenario of each stack's processes (issue #36: the stack under test and
    each reference apart), from readings keyed (worker, node); `groups`: {stack: its workers}.
    `runs`: the scenarios its workers ran; `cpu_per_run_s`: what one of its runs costs."""
    out = {}
    for name, ws in groups.items():
        cpu, runs = 0.0, 0
        for key, end in last.items():
            if key[0] not in ws:
                continue
            d = _delta(first.get(key, end), end)
            cpu += d["cpu"]
            runs += d["runs"] if key[1] == "scene_worker" else 0
        out[name] = {
            "cpu_per_scenario_s": cpu / scenarios,
            "runs": runs,
            "cpu_per_run_s": cpu / runs if runs else None,
        }
    return out
