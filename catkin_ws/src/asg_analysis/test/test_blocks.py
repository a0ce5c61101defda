"""Protocol v4's blocks (asg_analysis.blocks): one seed of every arm, the pilot's choice filled in,
an order drawn from the block's seed."""

import pytest
import os

import yaml

from asg_analysis import blocks

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", "..", ".."))


def test_a_block_holds_one_seed_of_every_arm_in_an_order_drawn_from_its_seed():
    with open(os.path.join(REPO, "experiments", "protocol-distinct-v4.yaml")) as f:
        protocol = yaml.safe_load(f)
    choice = {"method": "novelty-ts", "tabu_m": 5.0, "experiment": "experiments/exp1-route.yaml"}
    for k in range(5):
        cs = blocks.block(protocol, choice, k)
        assert sorted(c["arm"] for c in cs) == sorted(protocol["arms"]) and {c["seed"] for c in cs} == {30 + k}
        assert blocks.block(protocol, choice, k) == cs  # the same order every time
    orders = {tuple(c["arm"] for c in blocks.block(protocol, choice, k)) for k in range(5)}
    assert len(orders) > 1  # the order is drawn, not fixed
    default = next(c for c in blocks.block(protocol, choice, 0) if c["arm"] == "default")
    assert "method:=novelty-ts" in default["args"] and "tabu_m:=5" in default["args"]
    assert "experiment:=experiments/exp1-route.yaml" in default["args"]
    own = next(c for c in blocks.block(protocol, choice, 0) if c["arm"] == "random-own")
    assert "experiment:=experiments/exp1-route.yaml" in own["args"]  # random in the default's own space
    text = blocks.plan_text(blocks.block(protocol, choice, 2), 2)
    assert text.startswith("# block 2:") and text.count(" 300 train ") == len(protocol["arms"])


def test_the_transfer_plans_are_the_protocols_with_the_launchs_false():
    """protocol v4's transfer (Exp. 3, Exp. 6, gap_nav, the depth pair): each committed plan is the
    protocol's block, and gap_nav's `attribution: false` is written as the launch reads it (it
    wrote "False"); the depth pair runs with its release beside it."""
    attribution = {}
    for scene in ("exp3", "exp6", "gapnav", "depth"):
        with open(os.path.join(REPO, "experiments", f"protocol-distinct-v4-{scene}.yaml")) as f:
            protocol = yaml.safe_load(f)
        for k in range(3):
            cs = blocks.block(protocol, {}, k)
            with open(os.path.join(REPO, "results", "distinct_v4_transfer", f"{scene}-block-{k}.txt")) as f:
                assert f.read() == blocks.plan_text(cs, k)
        attribution[scene] = [a for c in cs for a in c["args"] if a.startswith("attribution:=")]
    assert attribution["gapnav"] == ["attribution:=false"] * 2
    assert attribution["depth"] == ["attribution:=release"] * 2


def test_a_block_past_the_seeds_is_refused(capsys, tmp_path):
    protocol = {"name": "x", "budget": 10, "arms": {"a": {"method": "random", "seeds": [1]}}}
    try:
        blocks.block(protocol, {}, 1)
    except ValueError as e:
        assert "arm a: block 1 but only 1 seeds" in str(e)
    else:
        raise AssertionError("no refusal")
    assert blocks.run([str(tmp_path / "none.yaml"), str(tmp_path / "c.json"), "0"]) == 2
    assert "none.yaml" in capsys.readouterr().err


def _export(path, name, seed, places):
    """A made-up pilot export of Exp. 1: 100 scenarios, a flaw finding on the first juniper at each
    of `places` (its x [m])."""
    import gzip
    import json

    camp = {"name": name, "seed": seed, "settings": "{}", "experiment": "exp1", "experiment_text": "x"}
    meshes = ["juniper"] * 4 + ["barberry"] * 4
    with gzip.open(path, "wt") as f:
        f.write(json.dumps({"campaign": camp}) + "\n")
        for j in range(100):
            hit = j < len(places)
            row = {
                "job": j,
                "termination": "COLLISION" if hit else "SUCCESS",
                "attribution": "flaw" if hit else "not_candidate",
                "meshes": meshes,
                "positions": [[places[j] if hit else 5.0, 50.0]] + [[5.0 + 10 * k, 95.0] for k in range(7)],
                "collision_with": 0 if hit else None,
                "trajectory_xy": [[20.0, 20.0], [50.0, 50.0]],
            }
            f.write(json.dumps(row) + "\n")


def test_choose_takes_the_larger_distinct_mean_then_the_5_m_figure(tmp_path):
    protocol = {
        "name": "t",
        "pilot": {
            "budget": 100,
            "search": {
                "near": {"method": "novelty-ts", "tabu_m": 2.0, "reward": "flaw", "experiment": "e1"},
                "far": {"method": "novelty-ts", "tabu_m": 5.0, "reward": "flaw", "experiment": "e2"},
                "few": {"method": "random", "reward": "flaw", "experiment": "e3"},
            },
        },
    }
    # near: 12 places 3 m apart (12 at 2 m, 6 at 5 m); far: 10 places 6 m apart (10 at 2 and 5 m)
    _export(tmp_path / "t-pilot-near-s20.jsonl.gz", "t-pilot-near-s20", 20, [3.0 * k for k in range(12)])
    _export(tmp_path / "t-pilot-far-s20.jsonl.gz", "t-pilot-far-s20", 20, [6.0 * k for k in range(10)])
    _export(tmp_path / "t-pilot-few-s20.jsonl.gz", "t-pilot-few-s20", 20, [6.0 * k for k in range(3)])
    c = blocks.choose(protocol, str(tmp_path))
    assert c["arms"]["near"]["mean_2m"] == 120.0 and c["arms"]["far"]["mean_2m"] == 100.0
    assert c["arm"] == "near"  # 20 per 1,000 ahead: no tie
    _export(tmp_path / "t-pilot-far-s20.jsonl.gz", "t-pilot-far-s20", 20, [6.0 * k for k in range(12)])
    c = blocks.choose(protocol, str(tmp_path))  # 120 against 120: a tie; far has more at 5 m (120 against 60)
    assert c["arm"] == "far" and c["tabu_m"] == 5.0 and c["experiment"] == "e2"


def test_one_translator_writes_every_plan_and_refuses_a_key_it_has_no_argument_for():
    from asg_analysis import protocol

    assert protocol.launch_args({"method": "novelty-ts", "tabu_m": 5.0, "attribution": False, "seed": 3}) == [
        "method:=novelty-ts",
        "tabu_m:=5",
        "seed:=3",
        "attribution:=false",
    ]
    with pytest.raises(protocol.ProtocolError, match="tabu"):
        protocol.launch_args({"tabu": 2})  # an arm's key under another name is refused, not dropped
