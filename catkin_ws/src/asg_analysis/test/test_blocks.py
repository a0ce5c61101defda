"""Protocol v4's blocks (asg_analysis.blocks): one seed of every arm, the pilot's choice filled in,
an order drawn from the block's seed."""

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
    assert "method:=novelty-ts" in default["args"] and "tabu:=5" in default["args"]
    assert "experiment:=experiments/exp1-route.yaml" in default["args"]
    own = next(c for c in blocks.block(protocol, choice, 0) if c["arm"] == "random-own")
    assert "experiment:=experiments/exp1-route.yaml" in own["args"]  # random in the default's own space
    text = blocks.plan_text(blocks.block(protocol, choice, 2), 2)
    assert text.startswith("# block 2:") and text.count(" 300 train ") == len(protocol["arms"])


def test_a_block_past_the_seeds_is_refused(capsys, tmp_path):
    protocol = {"name": "x", "budget": 10, "arms": {"a": {"method": "random", "seeds": [1]}}}
    try:
        blocks.block(protocol, {}, 1)
    except ValueError as e:
        assert "arm a: block 1 but only 1 seeds" in str(e)
    else:
        raise AssertionError("no refusal")
    assert blocks.main([str(tmp_path / "none.yaml"), str(tmp_path / "c.json"), "0"]) == 2
    assert "none.yaml" in capsys.readouterr().err
