"""Issue #37: a protocol file turned into campaign plans and read back against its exports, with
every deviation printed (in-process stand-in stacks, no ROS)."""

import json
import os

import pytest
import yaml

from asg_agent.analysis import protocol as pr
from asg_agent.analysis.export import export
from asg_agent.campaign.experiment import load_experiment
from asg_agent.campaign.fake_pool import FakePool
from asg_agent.campaign.loop import Campaign
from asg_agent.campaign.store import Store
from asg_agent.scoring import attribution as attr
from asg_agent.search.methods import make_method

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", "..", ".."))


def small_protocol(tmp_path):
    p = yaml.safe_load(open(os.path.join(REPO, "experiments", "protocol-round4.yaml")))
    p.update(name="t", budget=12)
    p["pilot"].update(seeds=[0], rewards=["proxy", "clearance"], route_bands_m=[2.5, 5.0])
    p["arms"] = {
        "default": {"method": "td3-per-asp", "reward": "pilot", "seeds": [1, 2]},
        "route-random": {"method": "route-random", "band_m": "pilot", "share": 1.0, "seeds": [1, 2]},
    }
    path = tmp_path / "protocol.yaml"
    path.write_text(yaml.safe_dump(p))
    return pr.load(str(path))


def run(tmp_path, store, c, collide, workers=3):
    """Campaign `c` of a plan on stand-in stacks: the stack under test collides on `collide`, the
    references never (so each collision is a flaw finding)."""
    exp = load_experiment(os.path.join(REPO, "experiments", "exp1.yaml"))
    options = {"band": c["band"], "share": 1.0} if c["band"] else None
    m = make_method(c["method"], exp, c["seed"], budget=c["budget"], options=options)
    settings = {
        "reward": c["reward"],
        "workers": [f"/w{i}" for i in range(workers)],
        "references": {"full": {}, "ground_truth": {}},
    }
    camp = Campaign(
        c["name"],
        exp,
        m,
        store,
        FakePool(2, gain=0.0, collide_jobs=collide),
        c["budget"],
        c["seed"],
        str(tmp_path / (c["name"] + ".ckpt")),
        slots=4,
        settings=settings,
        reward=c["reward"],
        references={attr.FULL: FakePool(1, gain=0.0, prefix="f"), attr.TRUTH: FakePool(1, gain=0.0, prefix="g")},
    )
    camp.start()
    camp.run(poll_timeout=0.0)
    export(store, c["name"], str(tmp_path / "out" / (c["name"] + ".jsonl.gz")))


def test_the_protocol_plans_chooses_and_analyses(tmp_path, monkeypatch):
    shipped = pr.load(os.path.join(REPO, "experiments", "protocol-round4.yaml"))
    confirm = pr.campaigns(shipped, "confirmatory", {"reward": "ttc", "band_m": 5.0})
    assert len(confirm) == 8 + 8 + 8 + 3 + 3
    assert {c["reward"] for c in confirm if c["arm"] == "default"} == {"ttc"}
    assert all("route_band:=5" in c["args"] for c in confirm if c["arm"] == "route-random")
    with pytest.raises(pr.ProtocolError, match="pilot's choice"):
        pr.campaigns(shipped, "confirmatory")

    p = small_protocol(tmp_path)
    store = Store(str(tmp_path / "s.sqlite"))
    (tmp_path / "out").mkdir()
    pilot = pr.campaigns(p, "pilot")
    assert [c["name"] for c in pilot] == [
        "t-pilot-reward-proxy-s0",
        "t-pilot-reward-clearance-s0",
        "t-pilot-band-2.5-s0",
        "t-pilot-band-5-s0",
    ]
    for c in pilot:  # clearance and the 5 m band find more (the stand-in collides where told)
        run(tmp_path, store, c, {1, 4, 6} if ("clearance" in c["name"] or "band-5" in c["name"]) else {3})
    ch = pr.choose(p, str(tmp_path / "out"))
    assert (ch["reward"], ch["band_m"]) == ("clearance", 5.0) and ch["deviations"] == []
    assert ch["rewards"] == {"proxy": 1000 / 12, "clearance": 3000 / 12}
    # A tie on the endpoint goes to more distinct failure modes (then to the earlier entry).
    from asg_agent.analysis import failure_modes as fm

    with monkeypatch.context() as m:
        m.setattr(pr, "per_seed", lambda rows, budget, cls: 5.0)  # every arm ties on the endpoint
        m.setattr(
            fm, "modes_of", lambda camp, rows, keep: [(i,) for i in range(3 if "clearance" in camp["name"] else 1)]
        )
        tie = pr.choose(p, str(tmp_path / "out"))
    assert tie["reward"] == "clearance" and tie["band_m"] == 2.5  # bands tie on modes too: the earlier one
    confirm = pr.campaigns(p, "confirmatory", ch)
    for c in confirm:
        collide = {2, 5, 8, 9} if c["arm"] == "default" else {7}
        run(tmp_path, store, c, collide, workers=2 if c["name"] == "t-route-random-s2" else 3)
    res = pr.analyse(p, str(tmp_path / "out"), ch)
    assert res["arms"]["default"]["per_seed"] == {1: 4000 / 12, 2: 4000 / 12}
    assert res["arms"]["route-random"]["per_seed"] == {1: 1000 / 12, 2: 1000 / 12}
    row = next(r for r in res["comparison"] if r["arm"] == "route-random")
    assert row["ratio"] == pytest.approx(4.0) and row["effect"] == 1.0
    # the campaign run with 2 workers under test is named, not hidden
    assert res["deviations"] == ["t-route-random-s2: 2 workers under test, the protocol says 3"]
    assert res["arms"]["default"]["distinct_modes"] >= 1 and 0 < res["arms"]["default"]["coverage"] <= 1
    os.remove(tmp_path / "out" / "t-default-s2.jsonl.gz")
    assert "t-default-s2: no export" in pr.analyse(p, str(tmp_path / "out"), ch)["deviations"][0]


def test_a_bad_protocol_is_named(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("name: x\n")
    with pytest.raises(pr.ProtocolError, match="lacks version"):
        pr.load(str(bad))
    p = yaml.safe_load(open(os.path.join(REPO, "experiments", "protocol-round4.yaml")))
    p["arms"]["random"]["seeds"] = [0, 10]
    bad.write_text(yaml.safe_dump(p))
    with pytest.raises(pr.ProtocolError, match="reuses pilot seeds"):
        pr.load(str(bad))
    assert json.loads(json.dumps(p))  # plain data
