"""asg_analysis.studies.hardening: the design loop's tables from evaluations and recorded suite runs."""

import os


def test_hardening_table_reads_evaluations_and_recorded_suite_outcomes(tmp_path):
    """analysis.hardening: per-pixel figures per arm from the evaluation files, pass rates from
    the outcomes `suite run --record` stored (a campaign's exported outcomes, with no digest, are
    not a recorded run), arms in the loop's order."""
    import json

    import yaml

    from asg_analysis.studies import hardening as ah

    fig = {"iou": {"non_traversable": 0.5}, "shadow_false_obstacle_rate": 0.1, "shadow_away_false_obstacle_rate": 0.05}
    for name, rnd in (("test", 1), ("heldout-findings", 1)):
        with open(tmp_path / f"evaluation-{name}-{rnd}.json", "w") as f:
            results = {"hardened-findings-1": fig, "flawed": dict(fig, shadow_false_obstacle_rate=0.3)}
            json.dump({"data": name, "frames": 10, "results": results}, f)  # evaluate_unet --json
    scen = [
        {"outcomes": {"flawed-bf16": {"termination": "COLLISION", "proxy": 1.0}, **outs}}
        for outs in (
            {
                "flawed-cl": {"termination": "COLLISION", "proxy": 1.0, "digest": "a"},
                "flawed": {"termination": "COLLISION", "proxy": 1.0, "digest": "a"},  # not harden.sh's
                "hardened-findings-1": {"termination": "SUCCESS", "proxy": 1.2, "digest": "b"},
            },
            {
                "flawed-cl": {"termination": "SUCCESS", "proxy": 3.5, "digest": "c"},  # proxy >= bound: fails
                "hardened-findings-1": {"termination": "SUCCESS", "proxy": 1.1, "digest": "d"},
            },
        )
    ]
    os.makedirs(tmp_path / "suite-exp1c")
    with open(tmp_path / "suite-exp1c" / "suite.yaml", "w") as f:
        yaml.safe_dump({"format_version": 1, "bound": 3.0, "scenarios": scen}, f)
    t = ah.table(str(tmp_path))
    assert list(t["arms"]) == ["flawed", "hardened-findings-1"]
    assert t["arms"]["flawed"]["suite-exp1c"] == {"passed": 0, "n": 2}
    assert t["arms"]["hardened-findings-1"]["suite-exp1c"] == {"passed": 2, "n": 2}
    assert t["arms"]["flawed"]["test"]["shadow_false_obstacle_rate"] == 0.3
    md = ah.markdown(t)
    assert "| flawed | 0.500 | 0.300 | 0.500 | 0.300 | 0 / 2 |" in md.splitlines()  # no suite-r4pilot column
    assert ah.run([str(tmp_path / "none")]) == 2
