"""What a campaign writes: exports and summaries that agree with the store, the collision reward,
the obstacle a run hit, differential and three-stack campaigns."""

import os
import time

import pytest

from asg_agent.campaign.loop import Campaign
from asg_agent.campaign.config import CampaignConfig
from asg_agent.records.experiment import load_experiment
from stand_in.fake_pool import FakePool
from asg_agent.search.methods import make_method
from asg_agent.records.store import Store


from stand_ins import EXP, DyingPool, Interrupt, campaign


def test_export_and_summary_agree_with_the_store(tmp_path):
    from asg_agent.records.export import counts, export, read_export

    c = campaign(tmp_path, "rep", FakePool(2, seed=8), total=30, method="random")
    c.start()
    c.run()
    out = str(tmp_path / "rep.jsonl.gz")
    assert export(c.store, "rep", out) == 30
    time.sleep(1.1)  # a gzip header with the time in it would differ now
    assert export(c.store, "rep", str(tmp_path / "again.jsonl.gz")) == 30
    assert open(out, "rb").read() == open(tmp_path / "again.jsonl.gz", "rb").read()  # byte-identical re-export
    head, rows = read_export(out)
    assert all(r["collision_with"] is None for r in rows if r["termination"] != "COLLISION")
    s = c.store.summary("rep")
    k = counts(rows)
    assert head["name"] == "rep"
    assert (k["scenarios"], k["proxy_ge_3"], k["proxy_ge_4"]) == (s["scenarios"], s["proxy_ge_3"], s["proxy_ge_4"])
    assert abs(k["max_proxy"] - s["max_proxy"]) < 1e-12


def test_the_collision_reward_adds_its_bonus_to_perception_collisions_only(tmp_path):
    """--reward collision (issue #27): the search learns from the proxy plus the bonus where the
    stack under test collided and the reference stack reached the goal (a perception collision, as
    every count defines it); the stored proxy stays the paper's."""
    from asg_agent.scoring.rewards import collision_reward

    assert collision_reward(1.2, "COLLISION", None, 2.0) == 3.2  # no reference: every collision
    assert collision_reward(1.2, "COLLISION", "SUCCESS", 2.0) == 3.2
    assert collision_reward(1.2, "COLLISION", "COLLISION", 2.0) == 1.2  # the stack's, not the perception's
    assert collision_reward(1.2, "SUCCESS", None, 2.0) == 1.2
    assert collision_reward(1.2, "COLLISION", "STUCK_TIMEOUT", 2.0) == 1.2  # the reference did not get through
    exp = load_experiment(EXP)
    store = Store(str(tmp_path / "r.sqlite"))
    c = Campaign(
        CampaignConfig(
            name="r",
            experiment=exp,
            method=make_method("random", exp, 3, budget=24),
            store=store,
            pool=FakePool(2, seed=1, collide_jobs={2, 5, 9}),
            total=24,
            seed=3,
            checkpoint=str(tmp_path / "r.ckpt"),
            slots=4,
            reward="collision",
            collision_bonus=1.5,
            references={"ground_truth": FakePool(2, seed=11, prefix="fake_ref", collide_jobs={9})},
            candidates="all",
        )
    )
    c.start()
    c.run(poll_timeout=0.0)
    rows = {r["job"]: r for r in store.rows("r")}
    assert len(rows) == 24
    for job, r in rows.items():
        bonus = 1.5 if job in (2, 5) else 0.0  # job 9: the reference collided too
        assert r["termination"] == ("COLLISION" if job in (2, 5, 9) else "SUCCESS")
        assert abs(r["reward"] - (r["proxy"] + bonus)) < 1e-12, job
    from stand_in.campaign import parse

    assert parse([EXP, "--fake-workers", "2", "--reward", "collision"]).collision_bonus == 2.0
    with pytest.raises(SystemExit):
        parse([EXP, "--fake-workers", "2", "--reward", "collision", "--collision-bonus", "nan"])
    for bad, match in (
        ({"reward": "collisions"}, "must be one of"),
        ({"reward": "collision", "collision_bonus": -1.0}, ">= 0"),
    ):
        with pytest.raises(ValueError, match=match):
            Campaign(
                CampaignConfig(
                    name="x",
                    experiment=exp,
                    method=make_method("random", exp, 3, budget=4),
                    store=store,
                    pool=FakePool(1),
                    total=4,
                    seed=3,
                    checkpoint=str(tmp_path / "x"),
                    **bad,
                )
            )


def test_the_export_names_the_obstacle_a_run_hit_by_its_index_in_positions():
    from asg_agent.records.export import collision_index

    req = {"structural": {"layouts": [{"instances": [{}, {}, {}]}, {"instances": [{}, {}]}]}}
    assert collision_index(req, "") is None
    assert collision_index(req, "0:2") == 2
    assert collision_index(req, "1:0") == 3 and collision_index(req, "1:1") == 4
    with pytest.raises(ValueError, match="names no obstacle"):
        collision_index(req, "1:2")
    with pytest.raises(ValueError, match="not 'layout:instance'"):
        collision_index(req, "juniper")


def test_complete_tells_a_finished_export_at_its_budget_and_park_names_bad_input(tmp_path, capsys):
    """What scripts/repro/campaigns.sh asks before running a plan line: `complete` exits 0 only for the
    export of a finished campaign holding at least the budget; `park` and `unpark` exit 2 naming
    what is wrong."""
    from asg_agent.cli.store import main
    from asg_agent.records.export import export

    c = campaign(tmp_path, "done", FakePool(2, seed=8), total=12, method="random")
    c.start()
    c.run()
    out = str(tmp_path / "done.jsonl.gz")
    export(c.store, "done", out)
    assert main(["complete", out, "12"]) == 0
    capsys.readouterr()
    assert main(["complete", out, "13"]) == 1  # a larger budget than it ran: not done
    assert "not complete: 12 of 13 scenarios" in capsys.readouterr().err
    assert main(["complete", str(tmp_path / "none.jsonl.gz"), "12"]) == 1
    assert "none.jsonl.gz: not complete: no such export" in capsys.readouterr().err
    cut = campaign(tmp_path, "cut", DyingPool(9, workers=2, seed=5), total=40, store=c.store)
    cut.start()
    with pytest.raises(Interrupt):
        cut.run()
    export(c.store, "cut", str(tmp_path / "cut.jsonl.gz"))
    assert main(["complete", str(tmp_path / "cut.jsonl.gz"), "1"]) == 1  # unfinished
    assert "not complete: campaign cut is unfinished" in capsys.readouterr().err
    store = c.store.path
    assert main(["park", "--unfinished-only", store, "done", str(tmp_path / "p.tar.xz")]) == 0
    assert not os.path.exists(tmp_path / "p.tar.xz") and "finished; not parked" in capsys.readouterr().out
    assert main(["park", store, "nope", str(tmp_path / "p.tar.xz")]) == 2
    assert "no campaign 'nope'" in capsys.readouterr().err
    assert main(["unpark", store, str(tmp_path / "done.jsonl.gz")]) == 2
    assert "not a parked campaign" in capsys.readouterr().err
    # `show`: the campaign's last screen again (docs/replay.md's first step), bad input named
    from asg_agent.cli.campaign import print_summary
    import io

    screen = io.StringIO()
    print_summary(c.store, "done", out=screen)
    assert main(["show", store, "done"]) == 0
    out = capsys.readouterr().out
    assert out == screen.getvalue() and "scene generator: random" in out
    assert out.index("terminations:") < out.index("the paper's proxy:")  # the proxy after the attribution
    assert main(["show", store, "nope"]) == 2
    assert "holds no campaign 'nope' (it holds: cut, done)" in capsys.readouterr().err
    assert main(["show", str(tmp_path / "none.sqlite"), "done"]) == 2
    assert "no such scenario store" in capsys.readouterr().err


def test_differential_campaign_learns_from_the_difference_and_repeats(tmp_path):
    """--reference-workers: every scenario runs on both stacks (here stand-ins that wiggle 0.8 and
    0.3 m per nearby obstacle); the stored reward is the proxy difference, the reference run is
    kept, and the same seed gives the same store whatever the two pools' speeds."""
    import json as _json

    digests = []
    for name, seed in (("d1", 1), ("d2", 2)):
        store = Store(str(tmp_path / "d.sqlite"))
        exp = load_experiment(EXP)
        c = Campaign(
            CampaignConfig(
                name=name,
                experiment=exp,
                method=make_method("td3-per-asp", exp, 4, budget=40),
                store=store,
                pool=FakePool(2, seed=seed),
                total=40,
                seed=4,
                checkpoint=str(tmp_path / f"{name}.ckpt"),
                slots=4,
                reward="differential",
                references={"ground_truth": FakePool(2, seed=seed + 10, gain=0.3, prefix="fake_ref")},
                candidates="all",
            )
        )
        c.start()
        c.run(poll_timeout=0.0)
        rows = list(store.rows(name))
        assert [r["job"] for r in rows] == list(range(40))
        for r in rows:
            ref = _json.loads(r["reference"])
            assert ref["worker"].startswith("/fake_ref_")
            assert abs(r["reward"] - (r["proxy"] - ref["proxy"])) < 1e-12
        assert any(r["reward"] > 0 for r in rows)  # the wigglier stack scores higher somewhere
        st = c.status()  # the progress bar's differential figures agree with the store
        assert st["diff_ge1"] == sum(r["reward"] >= 1 for r in rows)
        assert abs(st["diff_best"] - max(r["reward"] for r in rows)) < 1e-12
        digests.append([(r["job"], r["proxy"], r["reward"], r["request"]) for r in rows])
    assert digests[0] == digests[1]


def _attributed_campaign(exp, store, tmp_path):
    """60 random scenarios on a stand-in that wiggles much, each also run on a calmer reference."""
    return Campaign(
        CampaignConfig(
            name="a",
            experiment=exp,
            method=make_method("random", exp, 3, budget=60),
            store=store,
            pool=FakePool(2, seed=1, gain=6.0),
            total=60,
            seed=3,
            checkpoint=str(tmp_path / "a.ckpt"),
            slots=4,
            references={"ground_truth": FakePool(2, seed=11, gain=1.5, prefix="fake_ref")},
            candidates="all",
        )
    )


def test_attribution_counts_perception_and_stack_findings(tmp_path):
    """--reference-workers with the proxy reward (the default): the search learns from the stack
    under test's proxy, every scenario also runs on the reference stand-in, and the progress
    figures, the store's summary and a resumed campaign all count a finding (proxy >= 3) as the
    perception's when the reference stays below 2 and as the stack's when it reaches 3."""
    import json as _json

    store = Store(str(tmp_path / "a.sqlite"))
    exp = load_experiment(EXP)
    c = _attributed_campaign(exp, store, tmp_path)
    c.start()
    c.run(poll_timeout=0.0)
    rows = list(store.rows("a"))
    assert len(rows) == 60
    ref = {r["job"]: _json.loads(r["reference"])["proxy"] for r in rows}
    for r in rows:
        assert r["reward"] == r["proxy"]  # the paper's objective, not the difference
    perception = sum(r["proxy"] >= 3 and ref[r["job"]] < 2 for r in rows)
    stack = sum(r["proxy"] >= 3 and ref[r["job"]] >= 3 for r in rows)
    assert perception > 0 and stack > 0, (perception, stack)  # the stand-ins give both kinds
    st = c.status()
    assert (st["perception"], st["stack"]) == (perception, stack)
    s = store.summary("a")
    assert (s["attributed"], s["perception_ge3"], s["stack_ge3"]) == (60, perception, stack)
    assert s["differential_ge1"] == sum(r["proxy"] - ref[r["job"]] >= 1 for r in rows)
    # The compact export keeps the reference runs, and its counts are the store's.
    from asg_agent.records.export import counts, export, read_export

    export(store, "a", str(tmp_path / "a.jsonl.gz"))
    k = counts(read_export(str(tmp_path / "a.jsonl.gz"))[1])
    assert (k["attributed"], k["perception_ge3"], k["stack_ge3"], k["differential_ge1"]) == (
        60,
        perception,
        stack,
        s["differential_ge1"],
    )
    # Collisions are attributed too (the stand-ins never collide: make some). Jobs 0-4: the stack
    # under test collides, the reference drives through; jobs 5-6: both collide.
    assert (s["perception_collisions"], s["stack_collisions"]) == (0, 0)
    for job in range(7):
        r = next(x for x in rows if x["job"] == job)
        refd = dict(_json.loads(r["reference"]), termination="COLLISION" if job >= 5 else "SUCCESS")
        store.db.execute(
            "UPDATE scenarios SET termination = 'COLLISION', reference = ? WHERE campaign = 'a' AND job = ?",
            (_json.dumps(refd), job),
        )
    store.db.commit()
    s2 = store.summary("a")
    assert (s2["perception_collisions"], s2["stack_collisions"]) == (5, 2)
    export(store, "a", str(tmp_path / "a2.jsonl.gz"))
    k2 = counts(read_export(str(tmp_path / "a2.jsonl.gz"))[1])
    assert (k2["perception_collisions"], k2["stack_collisions"]) == (5, 2)
    # PLR < 0.999 is warned about only where the run reached the goal: a run that ended early is
    # extended by a straight line to the goal, which may pass through what it hit.
    base = s2["plr_below_0999"]
    store.db.execute("UPDATE scenarios SET plr = 0.99 WHERE campaign = 'a' AND job IN (0, 20)")
    store.db.commit()
    assert next(x for x in store.rows("a") if x["job"] == 20)["termination"] == "SUCCESS"
    assert store.summary("a")["plr_below_0999"] == base + 1  # job 20, not the collision of job 0
    # A resumed campaign takes its counts from the store.
    again = _attributed_campaign(exp, store, tmp_path)
    again.resume()
    assert (again.status()["perception"], again.status()["stack"]) == (perception, stack)
    with pytest.raises(ValueError, match="needs a reference stack"):
        Campaign(
            CampaignConfig(
                name="b",
                experiment=exp,
                method=make_method("random", exp, 3, budget=5),
                store=store,
                pool=FakePool(1),
                total=5,
                seed=3,
                checkpoint=str(tmp_path / "b.ckpt"),
                reward="differential",
            )
        )


def test_the_store_and_the_export_hold_repository_relative_paths(tmp_path):
    """Issue #68: results/ holds no machine's paths. A campaign stores its experiment file
    repository-relative; an export of an older store (absolute paths) writes them relative, and a
    store without an absolute path exports its settings byte for byte."""
    import gzip
    import json
    from types import SimpleNamespace

    from asg_agent.campaign.policy import campaign_settings
    from asg_agent.paths import REPO, in_repo
    from asg_agent.records.export import export, read_export

    a = SimpleNamespace(reward="proxy")
    s = campaign_settings(a, load_experiment(EXP), ["fake_0"], {}, "failures")
    assert s["experiment_file"] == s["experiment_repo_file"] == "experiments/exp1.yaml"
    assert in_repo(s["experiment_file"]) == os.path.join(REPO, "experiments", "exp1.yaml") == in_repo(EXP)

    store = Store(str(tmp_path / "store.sqlite"))
    old = {"experiment_file": EXP, "stack_file": os.path.join(REPO, "stacks", "depth.launch"), "total": 1}
    store.create_campaign("old", "random", "exp1", "", 0, old)
    other = {"experiment_file": "/elsewhere/asg/experiments/exp1.yaml", "experiment_repo_file": "experiments/exp1.yaml"}
    store.create_campaign("other", "random", "exp1", "", 0, other)
    store.create_campaign("new", "random", "exp1", "", 0, s)
    heads = {}
    for name in ("old", "other", "new"):
        export(store, name, str(tmp_path / f"{name}.jsonl.gz"))
        heads[name] = json.loads(read_export(str(tmp_path / f"{name}.jsonl.gz"))[0]["settings"])
    assert (heads["old"]["experiment_file"], heads["old"]["stack_file"]) == (
        "experiments/exp1.yaml",
        "stacks/depth.launch",
    )
    assert heads["other"]["experiment_file"] == "experiments/exp1.yaml"  # another checkout's
    with gzip.open(tmp_path / "new.jsonl.gz", "rt") as f:
        assert json.loads(f.readline())["campaign"]["settings"] == store.campaign("new")["settings"]


def test_reward_auto_stands_for_what_the_references_can_see_and_is_stored_resolved():
    """train.launch's default (issue #67): --reward auto is flaw with the unflawed stack's re-runs,
    regression with a release's, and (issue #78) the stack's own failures with none or ground
    truth alone; the parsed options (and so the store's record of the campaign) name the resolved
    reward."""
    from stand_in.campaign import parse
    from asg_agent.scoring import rewards

    assert rewards.for_roles(["full", "ground_truth"]) == "flaw"
    assert rewards.for_roles(["release"]) == "regression"
    assert rewards.for_roles(["ground_truth"]) == "failure" and rewards.for_roles([]) == "failure"
    assert parse([EXP, "--fake-workers", "2", "--reward", "auto"]).reward == "failure"
    # the failure reward: 1 for a failed run, graded below 0.5 by clearance, a finding at 1
    assert rewards.failure_reward("COLLISION", 0.0) == rewards.failure_reward("STUCK_TIMEOUT", 4.0) == 1.0
    assert rewards.GRADED_CAP > rewards.failure_reward("SUCCESS", 0.5) > rewards.failure_reward("SUCCESS", 3.0) > 0.0
    assert rewards.failure_reward("SUCCESS", 9.0) == 0.0 and rewards.REGISTRY["failure"].finding_at == 1.0
    assert rewards.AUTO not in rewards.REWARDS  # a name for a choice, never a reward of its own


@pytest.mark.parametrize("name", ["flaw_study3/flaw3-default-s10", "distinct_v4/dist4-route-random-s30"])
def test_read_export_gives_the_standard_librarys_values(name):
    """read_export parses with orjson: every value, type and float bit of a committed export is
    what json.loads gives (an attributed flaw-reward campaign and a proxy one)."""
    import gzip
    import json

    from asg_agent.paths import REPO
    from asg_agent.records.export import read_export

    path = os.path.join(REPO, "results", name + ".jsonl.gz")
    campaign_, rows = read_export(path)
    with gzip.open(path, "rt", encoding="utf-8") as f:
        lines = f.read().splitlines()
    assert json.loads(lines[0])["campaign"] == campaign_ and len(rows) == len(lines) - 1 > 100
    # dumps writes each float by repr (its shortest round trip) and keeps int apart from float
    assert json.dumps(rows) == json.dumps([json.loads(line) for line in lines[1:]])
