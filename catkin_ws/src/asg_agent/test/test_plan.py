"""cli.plan: a plan of campaigns run back to back, resumably (scripts/repro/campaigns.sh), with a
stand-in for train.sh that runs a real campaign loop on the stand-in simulator."""

import json
import os
import subprocess
import sys

import pytest

from asg_agent.records.export import read_export
from asg_agent.records.experiment import load_experiment
from stand_in.fake_pool import FakePool
from asg_agent.campaign.loop import Campaign as Loop
from asg_agent.campaign.config import CampaignConfig
from asg_agent.records.store import Store, checkpoint_path
from asg_agent.cli import plan
from asg_agent.search.methods import make_method

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", "..", ".."))

PLAN = """\
# a comment line
a-random-s0  40 train method:=random seed:=0 experiment:=experiments/exp1.yaml   # trailing comment
b-random-s1  30 train method:=random seed:=1 experiment:=experiments/exp1.yaml planner_config:=planner_fine.yaml
"""


def test_parse_plan_reads_lines_and_names_what_is_wrong():
    cs = plan.parse_plan(PLAN)
    assert [(c.name, c.scenarios, c.launch) for c in cs] == [("a-random-s0", 40, "train"), ("b-random-s1", 30, "train")]
    assert cs[0].args == ["method:=random", "seed:=0", "experiment:=experiments/exp1.yaml"]
    for text, why in [
        ("x 10", "p:1: expected NAME SCENARIOS LAUNCH"),
        ("x ten train", "p:1: SCENARIOS = 'ten': must be a whole number >= 1"),
        ("x 0 train", "must be a whole number >= 1"),
        ("x 5 train seed=1", "p:1: 'seed=1': launch arguments are key:=value"),
        ("x 5 train\n\nx 6 train", "p:3: campaign x is planned twice"),
    ]:
        with pytest.raises(plan.PlanError, match=why):
            plan.parse_plan(text, "p")


def test_launch_args_make_paths_absolute_and_take_the_store_out():
    c = plan.parse_plan(
        "n 5 train experiment:=experiments/exp1.yaml planner_config:=planner_fine.yaml "
        "store:=results/x.sqlite seed:=3 planner_config:=/abs/p.yaml"
    )[0]
    store, args = plan.launch_args(c, "/r", "/r/default.sqlite")
    assert store == "/r/results/x.sqlite"
    assert args == [
        "experiment:=/r/experiments/exp1.yaml",
        "planner_config:=/r/catkin_ws/src/asg_planner/config/planner_fine.yaml",
        "seed:=3",
        "planner_config:=/abs/p.yaml",
    ]


class Cut(Exception):
    pass


class CuttingPool(FakePool):
    def __init__(self, after, **kw):
        super().__init__(**kw)
        self.after, self.seen = after, 0

    def poll(self, timeout):
        out = super().poll(timeout)
        self.seen += len(out)
        if self.after is not None and self.seen > self.after:
            raise Cut()
        return out


def stand_in(cut_after):
    """A train.sh that runs the campaign on the stand-in simulator; its first call for each
    campaign is cut off after `cut_after` outcomes (status 1), as a stopped run would be."""
    calls = []

    def run(c, store_path, args, repo):
        seed = int(next(a for a in args if a.startswith("seed:=")).split(":=")[1])
        exp = load_experiment(next(a for a in args if a.startswith("experiment:=")).split(":=")[1])
        first = c.name not in [n for n, _ in calls]
        calls.append((c.name, args))
        store = Store(store_path)
        m = make_method("random", exp, seed, budget=c.scenarios)
        pool = CuttingPool(cut_after if first else None, workers=2, seed=seed)
        loop = Loop(
            CampaignConfig(
                name=c.name,
                experiment=exp,
                method=m,
                store=store,
                pool=pool,
                total=c.scenarios,
                seed=seed,
                checkpoint=checkpoint_path(store_path, c.name),
                slots=4,
                checkpoint_every=1,
            )
        )
        if store.campaign(c.name) is not None:
            loop.resume()
        else:
            loop.start()
        try:
            loop.run()
        except Cut:
            return 1
        return 0

    return run, calls


def test_a_plan_runs_is_stopped_parked_moved_and_finished_elsewhere(tmp_path):
    cs = plan.parse_plan(PLAN)
    here = plan.Places.of(str(tmp_path / "here"), "results/x")
    said = []
    run, calls = stand_in(cut_after=25)
    # First run: the first campaign is cut off; the plan stops there, with what it stored exported.
    assert plan.run_plan(cs, here, repo=REPO, runner=run, say=said.append) == 1
    assert [n for n, _ in calls] == ["a-random-s0"]
    c, rows = read_export(os.path.join(here.exports, "a-random-s0.jsonl.gz"))
    assert not c["finished"] and 0 < len(rows) < 40
    assert calls[0][1][-1] == "experiment:=" + os.path.join(REPO, "experiments", "exp1.yaml")
    # Parked (to commit), then the plan goes on in another clone: unparked, resumed, finished.
    assert plan.run_plan(cs, here, repo=REPO, park_only=True, say=said.append) == 0
    parked = os.path.join(here.parked, "a-random-s0.tar.xz")
    assert os.path.isfile(parked)
    assert "campaign b-random-s1: not in the store; not parked" in said
    there = plan.Places.of(str(tmp_path / "there"), "results/x")
    os.makedirs(there.parked)
    os.replace(parked, os.path.join(there.parked, "a-random-s0.tar.xz"))
    assert plan.run_plan(cs, there, repo=REPO, runner=run, say=said.append) == 1  # b is cut on its first call
    assert any(s.startswith("campaign a-random-s0: unparked,") for s in said)
    assert not os.path.exists(os.path.join(there.parked, "a-random-s0.tar.xz"))  # spent once finished
    assert plan.complete(os.path.join(there.exports, "a-random-s0.jsonl.gz"), 40)
    assert plan.run_plan(cs, there, repo=REPO, runner=run, say=said.append) == 0
    assert plan.complete(os.path.join(there.exports, "b-random-s1.jsonl.gz"), 30)
    n = len(calls)
    # Everything finished: a third run skips both, also with only the exports (a fresh clone).
    os.remove(there.store)
    assert plan.run_plan(cs, there, repo=REPO, runner=run, say=said.append) == 0
    assert len(calls) == n and said[-1].endswith("skipped")


def test_dry_lists_and_main_names_a_bad_plan(tmp_path, capsys):
    said = []
    cs = plan.parse_plan(PLAN)
    assert plan.run_plan(cs, plan.Places.of(str(tmp_path), "r"), repo=REPO, dry=True, only="^b-", say=said.append) == 0
    assert len(said) == 1 and said[0].startswith("campaign b-random-s1: 30 scenarios (train.launch")
    bad = tmp_path / "bad.txt"
    bad.write_text("x 5\n")
    assert plan.main([str(bad)]) == 2
    assert "bad.txt:1: expected NAME SCENARIOS LAUNCH" in capsys.readouterr().err
    assert plan.main([str(tmp_path / "none.txt")]) == 2
    assert "none.txt: cannot read" in capsys.readouterr().err


def test_a_stopped_plan_stops_its_campaign_and_everything_under_it(tmp_path):
    # `kill PLAN_PID` left train.sh, its master, workers and campaign running; now the plan sends
    # SIGTERM to the campaign's process group, waits for it, and ends with status 130.
    import signal
    import subprocess
    import sys
    import time

    fake = tmp_path / "repo"
    (fake / "scripts").mkdir(parents=True)
    log = tmp_path / "log"
    (fake / "scripts" / "train.sh").write_text(
        f"trap 'echo stopped >> {log}; exit 143' TERM\n"
        f"(trap 'echo child stopped >> {log}; exit 143' TERM; echo child up >> {log}; sleep 300 & wait) &\n"
        f"echo up >> {log}\nsleep 300 & wait\n"
    )
    code = (
        "import sys\nfrom asg_agent.cli import plan\nfrom asg_agent.cli.signals import stop_on_signals\n"
        "stop_on_signals()\n"
        f"sys.exit(plan.train(plan.Campaign('c', 10, 'train'), 's.sqlite', [], {str(fake)!r}))\n"
    )
    env = dict(
        os.environ,
        PYTHONPATH=os.path.join(REPO, "catkin_ws", "src", "asg_agent", "src")
        + os.pathsep
        + os.environ.get("PYTHONPATH", ""),
    )
    p = subprocess.Popen(
        [sys.executable, "-c", code], env=env, preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_IGN)
    )
    deadline = time.time() + 60
    while not (log.exists() and "child up" in log.read_text() and "up\n" in log.read_text()) and time.time() < deadline:
        time.sleep(0.05)
    p.send_signal(signal.SIGTERM)
    assert p.wait(timeout=60) == 130
    lines = log.read_text().splitlines()
    assert "stopped" in lines and "child stopped" in lines, lines


def test_each_run_records_the_cpu_time_of_its_process_tree(tmp_path):
    # issue #54, amendment 1: findings per CPU-hour count the CPU time a campaign's runs took (the
    # children the plan waited for), measured per run, not wall time x cores
    cs = plan.parse_plan(PLAN)[:1]
    here = plan.Places.of(str(tmp_path / "here"), "results/x")
    inner, _ = stand_in(cut_after=10)
    burn = "import time\nt = time.process_time()\nwhile time.process_time() - t < 0.4: pass\n"

    def run(c, store_path, args, repo):
        subprocess.run([sys.executable, "-c", burn], check=True)  # a campaign's own child, in CPU
        return inner(c, store_path, args, repo)

    assert plan.run_plan(cs, here, repo=REPO, runner=run, say=lambda s: None) == 1  # cut: one run
    assert plan.run_plan(cs, here, repo=REPO, runner=run, say=lambda s: None) == 0  # resumed, done
    c, _ = read_export(os.path.join(here.exports, "a-random-s0.jsonl.gz"))
    settings = json.loads(c["settings"]) if isinstance(c["settings"], str) else c["settings"]
    cpu = [e for e in settings["events"] if e["kind"] == "cpu"]
    assert [e["rc"] for e in cpu] == [1, 0]
    assert all(0.35 <= e["cpu_s"] < 30 and e["wall_s"] >= e["cpu_s"] * 0.5 for e in cpu)
    # one cpu event for each run (start, resume): what asg_analysis.protocol.measured_cpu_hours sums
    assert len(cpu) == sum(e["kind"] in ("start", "resume", "restart") for e in settings["events"])
