"""Issue #80 item 3: a campaign is built from one configuration object, named field by field at
every call site, and followed through one callback mechanism (campaign/config.py)."""

import ast
import glob
import os

import pytest

from asg_agent.campaign.config import CampaignCallback, CampaignConfig, FunctionCallback
from stand_in.fake_pool import FakePool
from asg_agent.campaign.loop import Campaign
from asg_agent.records.experiment import load_experiment
from asg_agent.records.store import Store
from asg_agent.search.methods import make_method

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", "..", ".."))
EXP = os.path.join(REPO, "experiments", "exp1.yaml")


class Recorder(CampaignCallback):
    def __init__(self):
        self.jobs, self.progress = [], 0

    def on_scenario(self, job, row, figures):
        self.jobs.append(job)
        assert row["job"] == job and "findings" in figures

    def on_progress(self, status):
        self.progress += 1


def test_callbacks_given_and_added_see_every_scenario_in_job_order(tmp_path):
    exp = load_experiment(EXP)
    first, later, seen = Recorder(), Recorder(), []
    c = Campaign(
        CampaignConfig(
            name="cb",
            experiment=exp,
            method=make_method("random", exp, 3, budget=12),
            store=Store(str(tmp_path / "s.sqlite")),
            pool=FakePool(2, seed=1),
            total=12,
            seed=3,
            checkpoint=str(tmp_path / "cb.ckpt"),
            callbacks=[first, FunctionCallback(progress=lambda st: seen.append(st["done"]))],
        )
    )
    c.add_callback(later)
    c.start()
    c.run(poll_timeout=0.0)
    assert first.jobs == later.jobs == list(range(12))
    assert first.progress == later.progress == len(seen) >= 12 and seen[-1] == 12
    with pytest.raises(TypeError, match="must be a CampaignCallback"):
        c.add_callback(lambda st: None)


def test_every_campaign_is_built_from_a_config_named_field_by_field():
    """Every Campaign(...) of the tree (the package, its tests, the analysis, tests/) takes one
    CampaignConfig(...) whose fields are all named: no positional call site is left."""
    roots = [os.path.join(REPO, "catkin_ws", "src"), os.path.join(REPO, "tests"), os.path.join(REPO, "scripts")]
    calls, bad = 0, []
    for root in roots:
        for path in glob.glob(os.path.join(root, "**", "*.py"), recursive=True):
            if "/build/" in path or "/devel/" in path:
                continue
            src = open(path, encoding="utf-8").read()
            if "Campaign" not in src:
                continue
            tree = ast.parse(src)
            local = {
                a.asname or a.name
                for n in ast.walk(tree)
                if isinstance(n, ast.ImportFrom) and n.module == "asg_agent.campaign.loop"
                for a in n.names
                if a.name == "Campaign"
            }
            for n in ast.walk(tree):
                if isinstance(n, ast.Call) and isinstance(n.func, ast.Name) and n.func.id in local:
                    calls += 1
                    arg = n.args[0] if len(n.args) == 1 and not n.keywords else None
                    ok = isinstance(arg, ast.Call) and getattr(arg.func, "id", "") == "CampaignConfig" and not arg.args
                    if not ok:
                        bad.append(f"{os.path.relpath(path, REPO)}:{n.lineno}")
    assert calls >= 25 and not bad, bad  # the tree holds 28 (the refused configurations share one helper)
    loop = open(os.path.join(REPO, "catkin_ws", "src", "asg_agent", "src", "asg_agent", "campaign", "loop.py")).read()
    methods = open(
        os.path.join(REPO, "catkin_ws", "src", "asg_agent", "src", "asg_agent", "search", "methods.py")
    ).read()
    assert "old home" not in loop and "old home" not in methods
