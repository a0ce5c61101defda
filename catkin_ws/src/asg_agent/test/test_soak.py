"""cli.soak and campaign.soak_check (issue #14's soak, in Python since issue #38): the killer's
draws, its kills and log, the two legs with a stand-in agent process, and the accounting."""

import collections
import os
import random
import sys
import time

from asg_agent.campaign import soak_check
from asg_agent.records.experiment import load_experiment
from stand_in.fake_pool import FakePool
from asg_agent.campaign.loop import Campaign as Loop
from asg_agent.campaign.config import CampaignConfig
from asg_agent.records.store import Store
from asg_agent.cli import soak
from asg_agent.search.methods import make_method

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", "..", ".."))


def test_victims_are_drawn_evenly_and_no_segmenter_where_there_is_none():
    v = soak.Victims(workers=4, segmented=3)
    rng = random.Random(0)
    draws = collections.Counter(v.draw(rng) for _ in range(8000))
    assert abs(draws["agent"] / 8000 - 0.25) < 0.02
    assert "/worker_3/segmenter" not in draws  # ground truth: no segmenter to kill
    for w in range(4):
        assert draws[f"/worker_{w}/scene_worker"] > 0 and draws[f"/worker_{w}/planner"] > 0
    for w in range(3):
        assert draws[f"/worker_{w}/segmenter"] > 0
    assert [v.draw(random.Random(5)) for _ in range(3)] == [v.draw(random.Random(5)) for _ in range(3)]


def test_the_killer_kills_what_it_finds_and_logs_each_kill(tmp_path):
    log = tmp_path / "kills.log"
    pids = {"/worker_0/scene_worker": 101, "/worker_0/planner": 102, "/worker_1/scene_worker": 103}
    killed = []

    def kill(pid, sig):
        if pid == 103:
            raise ProcessLookupError()  # gone between the lookup and the kill: not logged
        killed.append((pid, sig))

    k = soak.Killer(soak.Victims(2, 2), (0.001, 0.002), lambda: 7, str(log), seed=1, lookup=pids.get, kill=kill)
    k.start()
    time.sleep(0.5)
    k.stop()
    k.join(timeout=5)
    assert not k.is_alive()
    lines = [line.split() for line in log.read_text().splitlines()]
    assert lines and len(lines) == len(killed)
    for (t, victim, pid), (kpid, sig) in zip(lines, killed):
        assert int(pid) == kpid and sig == 9
        assert victim == "agent" and kpid == 7 or pids[victim] == kpid
    assert {v for _, v, _ in lines} <= {"agent", "/worker_0/scene_worker", "/worker_0/planner"}


def stand_in_agent(tmp_path, script):
    """An agent whose process runs `script` (Python) with the budget and --resume flag in argv."""
    calls = tmp_path / "calls.txt"

    def command(budget, resume):
        return [sys.executable, "-c", script, str(calls), str(budget), "1" if resume else "0"]

    return soak.Agent(command, str(tmp_path / "agent.log")), calls


def test_leg_one_restarts_a_dead_agent_with_resume_and_kills_it_at_the_deadline(tmp_path):
    # The first start exits at once (killed); the next ones run past the deadline.
    script = (
        "import sys, time\n"
        "open(sys.argv[1], 'a').write(sys.argv[2] + ' ' + sys.argv[3] + '\\n')\n"
        "n = len(open(sys.argv[1]).read().splitlines())\n"
        "time.sleep(0 if n == 1 else 60)\n"
    )
    agent, calls = stand_in_agent(tmp_path, script)
    kills = tmp_path / "kills.log"
    killer = soak.Killer(soak.Victims(2, 2), (100, 100), agent.pid, str(kills), lookup=lambda n: None)
    t0 = time.time()
    soak.leg_one(agent, killer, time.time() + 3.0, False, str(kills), poll_s=0.1)
    assert time.time() - t0 < 20
    started = [line.split() for line in calls.read_text().splitlines()]
    assert started[0] == [str(soak.BIG), "0"] and started[1] == [str(soak.BIG), "1"]
    assert "agent-final" in kills.read_text()
    assert "restarting with --resume" in open(agent.log_path).read()
    assert agent.pid() is None and not killer.is_alive()


def test_leg_two_resumes_with_the_cut_budget_until_the_campaign_finishes(tmp_path):
    script = (
        "import sys\n"
        "open(sys.argv[1], 'a').write(sys.argv[2] + ' ' + sys.argv[3] + '\\n')\n"
        "sys.exit(0 if len(open(sys.argv[1]).read().splitlines()) >= 3 else 1)\n"
    )
    agent, calls = stand_in_agent(tmp_path, script)
    soak.leg_two(agent, 57, retry_s=0.01)
    assert calls.read_text().splitlines() == ["57 1"] * 3
    assert "draining: budget cut to 57 scenarios" in open(agent.log_path).read()


def test_the_report_counts_lost_and_doubled_scenarios(tmp_path):
    exp = load_experiment(os.path.join(REPO, "experiments", "exp1.yaml"))
    store = Store(str(tmp_path / "soak.sqlite"))
    m = make_method("random", exp, 1, budget=20)
    loop = Loop(
        CampaignConfig(
            name="soak",
            experiment=exp,
            method=m,
            store=store,
            pool=FakePool(2, seed=1),
            total=20,
            seed=1,
            checkpoint=str(tmp_path / "soak.ckpt"),
            slots=4,
        )
    )
    loop.start()
    loop.run()
    kills = tmp_path / "kills.log"
    kills.write_text("1 /worker_0/planner 5\n2 agent 6\n3 /worker_1/planner 7\n")
    log = tmp_path / "agent.log"
    log.write_text("x agent exited: restarting with --resume\njob 3: scene worker died, retrying elsewhere\n")
    res = soak_check.report(store.path, "soak", 20, str(kills), str(log), 0.0, 7200.0)
    assert (res["lost"], res["duplicates"], res["finished"], res["hours"]) == (0, 0, True, 2.0)
    assert res["kills"] == {"planner": 2, "agent": 1} and res["agent_restarts"] == 1
    assert res["retries_by_reason"] == {"scene worker died": 1}
    assert soak_check.passed(res)
    store.db.execute("DELETE FROM scenarios WHERE campaign = 'soak' AND job = 4")
    store.db.commit()
    res = soak_check.report(store.path, "soak", 20, str(kills), str(log), 0.0, 7200.0)
    assert res["lost"] == 1 and not soak_check.passed(res)


def test_retries_are_sorted_by_the_workers_current_wording():
    """Round 7's soak counted 16 of its 26 re-queues as "other": since issue #68 the worker names a
    stack node whose process changed ("planner: restarted or gone ...") before what its protocol saw."""
    lines = [
        "[campaign] job 176 failed on /worker_0 (segmenter: restarted or gone during the run (the master's URI"
        " for it changed); no labels for the camera frame at t = 6.867 s within 10.0 s (wall clock)); retrying elsewhere",
        "[campaign] job 2208 failed on /worker_0 (planner: restarted or gone during the run (the master's URI for"
        " it changed); no command for control tick t = 8.600 s within 10.0 s (wall clock)); retrying elsewhere",
        "[campaign] job 9 failed on /worker_1 (full reference: planner: restarted or gone during the run); retrying elsewhere",
        "[campaign] job 117 failed on /worker_2 (full reference: /worker_2: goal ended LOST without a result); retrying elsewhere",
        "[campaign] job 5 failed on /worker_1 (segmenter: no labels for the camera frame); retrying elsewhere",
    ]
    reasons = [soak_check.reason(line) for line in lines]
    assert reasons == ["segmenter restarted", "planner restarted", "planner restarted", "goal lost", "segmenter silent"]
    assert soak_check.reason("[campaign] job 1 failed on /worker_0 (something new); retrying elsewhere") == "other"
