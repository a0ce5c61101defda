"""Run a plan of campaigns back to back, resumably (scripts/repro/campaigns.sh is its wrapper).

A plan is a text file, one campaign a line: `NAME SCENARIOS LAUNCH ARGS...` (LAUNCH: a launch file
of asg_bringup without `.launch`, normally `train`; ARGS: its `key:=value` arguments; `#` starts a
comment). For each line, in order: a campaign whose committed export is finished at its budget is
skipped (also on a fresh clone without the store); else it is run, or resumed where it stopped,
through scripts/train.sh, then exported to EXPORTS/NAME.jsonl.gz. Stop it at any moment (Ctrl-C,
or `kill` of the plan's process: the campaign under way saves its state and is exported as far as
it went); run it again to go on. `--park` packs each unfinished campaign into
EXPORTS/parked/NAME.tar.xz (a few MB, to commit); the next run, here or on another clone, unparks
it first and goes on from there.

    python3 -m asg_agent.cli.plan PLAN [--only REGEX] [--exports results/depth] [--dry] [--park]

Paths in ARGS: `experiment:=` and `store:=` are relative to the repository; `planner_config:=` is
a file of asg_planner/config unless it holds a `/`. Without --exports the exports go to
results/campaigns and the store is results/campaigns/exp11.sqlite (issue #11's plan).
"""

import argparse
import os
import re
import resource
import signal
import time
import subprocess
import sys
from dataclasses import dataclass, field
from typing import Callable, List, Optional

from asg_agent.cli.signals import stop_on_signals

from asg_agent.paths import REPO


FIELDS = ("NAME", "SCENARIOS", "LAUNCH")  # the words a plan line starts with, then ARGS


class PlanError(ValueError):
    """A plan file that cannot be run, with the line that is wrong."""


@dataclass
class Campaign:
    name: str
    scenarios: int
    launch: str
    args: List[str] = field(default_factory=list)


def parse_plan(text: str, source: str = "plan") -> List[Campaign]:
    out, names = [], set()
    for k, line in enumerate(text.splitlines(), 1):
        words = line.split("#", 1)[0].split()
        if not words:
            continue
        if len(words) < len(FIELDS):
            raise PlanError(f"{source}:{k}: expected NAME SCENARIOS LAUNCH [ARGS...], got {line.strip()!r}")
        name, n, launch, args = words[0], words[1], words[2], words[3:]
        if not n.isdigit() or int(n) < 1:
            raise PlanError(f"{source}:{k}: SCENARIOS = {n!r}: must be a whole number >= 1")
        if name in names:
            raise PlanError(f"{source}:{k}: campaign {name} is planned twice")
        bad = [a for a in args if ":=" not in a]
        if bad:
            raise PlanError(f"{source}:{k}: {bad[0]!r}: launch arguments are key:=value")
        names.add(name)
        out.append(Campaign(name, int(n), launch, args))
    return out


@dataclass
class Places:
    exports: str
    store: str
    parked: str

    @classmethod
    def of(cls, repo: str, exports: str = "") -> "Places":
        if exports:
            base = os.path.join(repo, exports)
            return cls(base, os.path.join(base, "campaigns.sqlite"), os.path.join(base, "parked"))
        base = os.path.join(repo, "results", "campaigns")
        return cls(base, os.path.join(base, "exp11.sqlite"), os.path.join(repo, "results", "parked"))


def launch_args(c: Campaign, repo: str, default_store: str):
    """(store, arguments for train.sh) of a campaign: paths made absolute, store:= taken out."""
    store, out = default_store, []
    for a in c.args:
        key, value = a.split(":=", 1)
        if key == "store":
            store = os.path.join(repo, value)
        elif key == "experiment":
            out.append(f"experiment:={os.path.join(repo, value)}")
        elif key == "planner_config":
            path = value if "/" in value else os.path.join(repo, "catkin_ws", "src", "asg_planner", "config", value)
            out.append(f"planner_config:={path}")
        else:
            out.append(a)
    return store, out


def complete(export_path: str, scenarios: int) -> bool:
    """True when the export is of a finished campaign of at least `scenarios` scenarios."""
    from asg_agent.records.export import read_export

    if not os.path.isfile(export_path):
        return False
    c, rows = read_export(export_path)
    return bool(c["finished"]) and len(rows) >= scenarios


def train(c: Campaign, store: str, args: List[str], repo: str) -> int:
    """The campaign through scripts/train.sh (its master, workers and campaign node), resumed."""
    # ASG_BUILT: campaigns.sh installed and built once; train.sh skips its own check, so that
    # the campaign's measured CPU time (cpu_event) is the campaign's alone
    env = dict(os.environ, ASG_LAUNCH=c.launch, ASG_STORE=store, ASG_BUILT="1")
    cmd = ["bash", os.path.join(repo, "scripts", "train.sh"), str(c.scenarios), f"name:={c.name}", "resume:=true"]
    # its own process group: a stopped plan stops the campaign, its workers and its master with it
    p = subprocess.Popen(cmd + args, env=env, stdin=subprocess.DEVNULL, start_new_session=True)
    try:
        return p.wait()
    except KeyboardInterrupt:  # the plan was stopped (stop_on_signals): the campaign saves and ends
        os.killpg(p.pid, signal.SIGTERM)
        p.wait()
        return 130


def children_cpu_s() -> float:
    """[s] user + system CPU time of this process's finished children and all they waited for
    (train.sh, its roslaunch, the master, workers, references and the campaign node)."""
    ru = resource.getrusage(resource.RUSAGE_CHILDREN)
    return ru.ru_utime + ru.ru_stime


def cpu_event(cpu_s: float, wall_s: float, rc: int) -> dict:
    """The event a plan records in a campaign's store after each of its runs: the CPU seconds
    and wall seconds that run took (issue #54's amendment 1: findings per CPU-hour count these,
    not wall time x cores, which grows with whatever else shares the machine)."""
    return {"kind": "cpu", "cpu_s": round(cpu_s, 3), "wall_s": round(wall_s, 3), "rc": rc, "time": time.time()}


def run_plan(
    plan: List[Campaign],
    places: Places,
    repo: str = REPO,
    only: str = ".",
    dry: bool = False,
    park_only: bool = False,
    runner: Callable = train,
    say: Callable[[str], None] = lambda s: print(f"[asg] {s}", flush=True),
) -> int:
    from asg_agent.records.export import export
    from asg_agent.records.store import Store, checkpoint_path, park, unpark

    for c in plan:
        if not re.search(only, c.name):
            continue
        store, args = launch_args(c, repo, places.store)
        export_path = os.path.join(places.exports, f"{c.name}.jsonl.gz")
        parked = os.path.join(places.parked, f"{c.name}.tar.xz")
        if park_only:
            row = Store(store).campaign(c.name) if os.path.isfile(store) else None
            if row is None or row["finished"]:
                say(f"campaign {c.name}: " + ("not in the store" if row is None else "finished") + "; not parked")
                continue
            os.makedirs(places.parked, exist_ok=True)
            n = park(Store(store), c.name, checkpoint_path(store, c.name), parked)
            say(f"campaign {c.name}: parked, {n} scenarios and its checkpoint in {parked}")
            continue
        if not os.path.isfile(parked) and complete(export_path, c.scenarios):
            say(f"campaign {c.name}: finished at {c.scenarios} scenarios (export {export_path}); skipped")
            continue
        say(f"campaign {c.name}: {c.scenarios} scenarios ({c.launch}.launch {' '.join(args)}; store {store})")
        if dry:
            continue
        if os.path.isfile(parked):
            os.makedirs(os.path.dirname(store), exist_ok=True)
            n = unpark(Store(store), parked)
            say(f"campaign {c.name}: " + ("already in the store" if n is None else f"unparked, {n} scenarios"))
        before, t0 = children_cpu_s(), time.time()
        rc = runner(c, store, args, repo)
        store_obj = Store(store)
        if store_obj.campaign(c.name) is not None:
            store_obj.record_event(c.name, cpu_event(children_cpu_s() - before, time.time() - t0, rc))
            n = export(store_obj, c.name, export_path)
            say(f"campaign {c.name}: {n} scenarios exported to {export_path}")
        if rc != 0:  # the plan stops here; run it again to go on
            say(f"campaign {c.name}: train.sh ended with status {rc}; the plan stops")
            return 1
        # Finished: the export is the record, the parked copy is spent.
        if complete(export_path, c.scenarios) and os.path.isfile(parked):
            os.remove(parked)
    return 0


def main(argv: Optional[List[str]] = None) -> int:
    p = argparse.ArgumentParser(prog="asg_agent.cli.plan", description=__doc__.split("\n\n")[0])
    p.add_argument("plan", nargs="?", default=os.path.join(REPO, "results", "campaign_plan.txt"))
    p.add_argument("--only", default=".", help="only the campaigns whose name matches this regex")
    p.add_argument("--exports", default="", help="folder (under the repository) of the exports, store and parked")
    p.add_argument("--dry", action="store_true", help="only list what would run")
    p.add_argument("--park", action="store_true", help="park the unfinished campaigns (to commit)")
    a = p.parse_args(argv)
    try:
        with open(a.plan, encoding="utf-8") as f:
            plan = parse_plan(f.read(), a.plan)
    except OSError as e:
        print(f"plan: {a.plan}: cannot read ({e.strerror})", file=sys.stderr)
        return 2
    except PlanError as e:
        print(f"plan: {e}", file=sys.stderr)
        return 2
    stop_on_signals()
    try:
        return run_plan(plan, Places.of(REPO, a.exports), only=a.only, dry=a.dry, park_only=a.park)
    except KeyboardInterrupt:
        print("plan: stopped; run it again to go on", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
