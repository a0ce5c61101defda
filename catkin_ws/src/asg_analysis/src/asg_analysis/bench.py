"""`bench`: where a campaign's time goes (no ROS imports; docs/benchmarks.md).

The scene workers, segmenters and planners publish cumulative stage timers (asg_msgs/StageTimes);
the campaign times its own loop (campaign.Stages). `breakdown` turns the readings taken at the
start and the end of a campaign into per-scenario seconds per stage, the rate, and the bound the
U-Net alone sets; `table` renders one or several breakdowns as Markdown.

    python3 -m asg_analysis bench table results/bench/*.json
"""

import argparse
import json
import os
import statistics
import sys
from typing import List

from asg_agent.records.stage_costs import transport

PROG = "python3 -m asg_analysis bench"


ROWS = [  # (label, key in per_scenario_s)
    ("scene build + announce", "scene_worker.build"),
    ("stack acknowledgements", "scene_worker.acks"),
    ("render (camera + labels pass)", "scene_worker.render"),
    ("publish (worker)", "scene_worker.publish"),
    ("physics", "scene_worker.physics"),
    ("result assembly", "scene_worker.result"),
    ("segmenter: decode", "segmenter.decode"),
    ("segmenter: U-Net inference", "segmenter.inference"),
    ("segmenter: publish", "segmenter.publish"),
    ("planner: reset", "planner.reset"),
    ("planner: vote insertion", "planner.votes"),
    ("planner: planning + PD", "planner.plan"),
    ("planner: publish", "planner.publish"),
    ("agent: proposal", "agent.propose"),
    ("agent: TD3 update", "agent.update"),
    ("agent: proxy", "agent.proxy"),
    ("agent: store write", "agent.store"),
    ("agent: checkpoint", "agent.checkpoint"),
    ("agent: dispatch", "agent.dispatch"),
]


def table(runs: List[dict], labels: List[str]) -> str:
    head = "| per scenario (s, summed over workers) | " + " | ".join(labels) + " |"
    lines = [head, "|" + "---|" * (len(runs) + 1)]
    for label, key in ROWS:
        if any(key in r["per_scenario_s"] for r in runs):
            lines.append(f"| {label} | " + " | ".join(f"{r['per_scenario_s'].get(key, 0.0):.3f}" for r in runs) + " |")
    lines.append(
        "| worker waiting for the stack (lockstep) | "
        + " | ".join(f"{r['per_scenario_s'].get('scene_worker.wait', 0.0):.3f}" for r in runs)
        + " |"
    )
    lines.append(
        "| of which transport and scheduling (wait - stack work on the critical path) | "
        + " | ".join(f"{transport(r['per_scenario_s']):.3f}" for r in runs)
        + " |"
    )
    for kind in ("scene_worker", "segmenter", "planner", "agent"):
        lines.append(
            f"| CPU: {kind} process | "
            + " | ".join(f"{r['cpu_per_scenario_s'].get(kind, 0.0):.3f}" for r in runs)
            + " |"
        )
    for name in sorted({k for r in runs for k in r.get("stacks", {})}, key=lambda k: (k != "under test", k)):
        lines.append(
            f"| CPU: {name} stack, all its processes (a run of it) | "
            + " | ".join(
                (
                    f"{r['stacks'][name]['cpu_per_scenario_s']:.3f} ({r['stacks'][name]['cpu_per_run_s'] or 0:.2f})"
                    if name in r.get("stacks", {})
                    else "-"
                )
                for r in runs
            )
            + " |"
        )
    summary = [
        ("share of scenarios re-run on the references", "{rerun_share:.1%}"),
        ("scenarios", "{scenarios}"),
        ("wall (s)", "{wall_s:.0f}"),
        ("**scenarios an hour**", "**{rate_per_hour:.0f}**"),
        ("simulated s per wall s per worker", "{sim_s_per_wall_s_per_worker:.2f}"),
        ("camera frames per scenario", "{frames_per_scenario:.0f}"),
        ("U-Net ms per frame (in the campaign)", "{inference_ms_per_frame:.1f}"),
        ("inference-only bound (an hour)", "{inference_bound_per_hour:.0f}"),
        ("rate / bound", "{fraction_of_bound:.0%}"),
        ("rate / paper's 625 an hour", "{paper_ratio:.2f}x"),
    ]
    for label, fmt in summary:
        cells = []
        for r in runs:
            try:
                cells.append(fmt.format(**r))
            except KeyError:
                cells.append("-")
        lines.append(f"| {label} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def before_after(before: List[dict], after: List[dict]) -> dict:
    """Two sets of runs of one bench (code before and after a change, taken in turn): the median
    and range of each side's scenarios an hour and CPU [s] of the stack under test a scenario, and
    the ratio of the medians (after / before)."""

    def side(runs):
        rate = sorted(r["rate_per_hour"] for r in runs)
        cpu = sorted(r["stacks"]["under test"]["cpu_per_scenario_s"] for r in runs)
        return {"rate": (statistics.median(rate), rate[0], rate[-1]), "cpu": (statistics.median(cpu), cpu[0], cpu[-1])}

    b, a = side(before), side(after)
    return {"before": b, "after": a, "rate_ratio": a["rate"][0] / b["rate"][0], "cpu_ratio": a["cpu"][0] / b["cpu"][0]}


def before_after_sentence(c: dict) -> str:
    """The figures of before_after as docs/benchmarks.md states them (a test compares the two)."""
    b, a = c["before"], c["after"]
    return (
        f"scenarios an hour, median (range): before {b['rate'][0]:,.0f} ({b['rate'][1]:,.0f}-{b['rate'][2]:,.0f}), "
        f"after {a['rate'][0]:,.0f} ({a['rate'][1]:,.0f}-{a['rate'][2]:,.0f}), after / before {c['rate_ratio']:.3f}; "
        f"CPU of the stack under test a scenario [s]: before {b['cpu'][0]:.3f} ({b['cpu'][1]:.3f}-{b['cpu'][2]:.3f}), "
        f"after {a['cpu'][0]:.3f} ({a['cpu'][1]:.3f}-{a['cpu'][2]:.3f}), after / before {c['cpu_ratio']:.3f}"
    )


def predict(ms_per_frame: float, non_unet: List[dict], shape: List[dict], scenarios: int, cores: int) -> dict:
    """[min] what a campaign of `scenarios` should take on a CPU where the U-Net costs
    `ms_per_frame` [ms CPU a frame], from benches of that CPU without the U-Net (`non_unet`: the
    worker and planner of a run, and the agent, CPU a scenario) and benches giving the campaign's
    shape (`shape`: camera frames a scenario, share of scenarios re-run on the references), medians
    of each. A scenario costs a run of the stack under test (U-Net + worker and planner), the
    agent's share, and for the re-run share a `full` run (the same cost) and a ground-truth run
    (worker and planner only); the cores are kept busy (the three-stack bench reached 98 % of its
    CPU ceiling), so the minutes are that CPU over the cores."""
    frames = statistics.median(r["frames_per_scenario"] for r in shape)
    share = statistics.median(r["rerun_share"] for r in shape)
    run = statistics.median(r["stacks"]["under test"]["cpu_per_run_s"] for r in non_unet)
    agent = statistics.median(r["cpu_per_scenario_s"]["agent"] for r in non_unet)
    unet = frames * ms_per_frame / 1000.0
    cpu = unet + run + agent + share * ((unet + run) + run)
    return {
        "frames": frames,
        "rerun_share": share,
        "run_without_unet_s": run,
        "agent_s": agent,
        "unet_s": unet,
        "cpu_per_scenario_s": cpu,
        "minutes": scenarios * cpu / cores / 60.0,
        "scenarios": scenarios,
        "cores": cores,
        "ms_per_frame": ms_per_frame,
    }


def predict_sentence(r: dict) -> str:
    return (
        f"at {r['ms_per_frame']:g} ms a frame: {r['frames']:.0f} frames x {r['ms_per_frame']:g} ms = {r['unet_s']:.2f} s "
        f"of U-Net, + {r['run_without_unet_s']:.2f} s of worker and planner, + {r['agent_s']:.2f} s of agent, + "
        f"{100 * r['rerun_share']:.0f} % re-run on the references; {r['cpu_per_scenario_s']:.2f} s of CPU a scenario, "
        f"{r['scenarios']} scenarios on {r['cores']} cores: {r['minutes']:.1f} minutes"
    )


def run(argv=None):
    p = argparse.ArgumentParser(prog=PROG, description="Markdown table of bench breakdowns (docs/benchmarks.md)")
    sub = p.add_subparsers(dest="cmd", required=True)
    t = sub.add_parser("table", help="one column per breakdown JSON")
    t.add_argument("files", nargs="+")
    ba = sub.add_parser("before-after", help="medians of runs before and after a change (TAG-before-K, TAG-after-K)")
    ba.add_argument("files", nargs="+", help="breakdown JSONs; a name with -before- is a run of the code before")
    pr = sub.add_parser("predict", help="minutes of a campaign on a CPU from its U-Net ms a frame (predict())")
    pr.add_argument("--ms-per-frame", type=float, required=True, help="[ms] CPU of one U-Net frame on that CPU")
    pr.add_argument("--non-unet", nargs="+", required=True, help="bench JSONs of that CPU with ground-truth labels")
    pr.add_argument("--shape", nargs="+", required=True, help="bench JSONs with the U-Net and three-stack attribution")
    pr.add_argument("--scenarios", type=int, default=150)
    pr.add_argument("--cores", type=int, default=2)
    a = p.parse_args(argv)
    if a.cmd == "predict":
        try:
            load = [[json.load(open(f)) for f in fs] for fs in (a.non_unet, a.shape)]
        except (OSError, ValueError) as e:
            print(f"bench: {e}", file=sys.stderr)
            return 2
        print(predict_sentence(predict(a.ms_per_frame, load[0], load[1], a.scenarios, a.cores)))
        return 0
    runs, labels = [], []
    for path in a.files:
        try:
            with open(path) as f:
                runs.append(json.load(f))
        except (OSError, ValueError) as e:
            print(f"bench: {path}: {e}", file=sys.stderr)
            return 2
        labels.append(runs[-1].get("label") or os.path.splitext(os.path.basename(path))[0])
    if a.cmd == "before-after":
        sides = ["-before-" in os.path.basename(f) for f in a.files]
        if all(sides) or not any(sides):
            print("bench: before-after needs runs of both sides (names with -before- and without)", file=sys.stderr)
            return 2
        c = before_after([r for r, s in zip(runs, sides) if s], [r for r, s in zip(runs, sides) if not s])
        print(before_after_sentence(c))
        return 0
    print(table(runs, labels))
    return 0
