"""asg_analysis.studies.hardening picture: a suite scene with the paths driven before and after, drawn
from `suite run --json` results (the suite is the agent's stand-in one, built as its tests do)."""

import json
import os
import sys

AGENT_TEST = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "asg_agent", "test")
sys.path.insert(0, AGENT_TEST)

from test_suite import campaign_export, export_run_record_and_regress  # noqa: E402,F401  (a fixture)

from asg_analysis.studies import hardening  # noqa: E402


def test_the_picture_draws_a_failure_before_and_after(tmp_path, campaign_export, capsys):  # noqa: F811
    out, res2 = export_run_record_and_regress(tmp_path, campaign_export)
    # The JSON keeps each path driven (10 Hz): a failure before and after drawn from two results.
    with open(tmp_path / "r.json") as f:
        failed = json.load(f)
    assert failed[0]["fails"] and len(failed[0]["trajectory_xy"]) >= 2
    passed = json.loads(json.dumps(res2, default=str))
    png = str(tmp_path / "before_after.png")
    args = ["picture", out, failed[0]["file"], png, f"before={tmp_path / 'r.json'}"]
    with open(tmp_path / "after.json", "w") as f:
        json.dump(passed, f)
    assert hardening.run(args + [f"after={tmp_path / 'after.json'}"]) == 0 and os.path.getsize(png) > 10_000
    # issue #68: exit 2 alone also held for another error (a spec without "=" then opened the file "",
    # exit 2 too): each refusal's reason is asserted
    capsys.readouterr()
    assert hardening.run(["picture", out, "no-such.yaml", png, f"before={tmp_path / 'r.json'}"]) == 2
    assert "'no-such.yaml': not a scenario of" in capsys.readouterr().err
    assert hardening.run(args + ["after"]) == 2  # LABEL=RESULTS.json, named as wrong
    assert "'after': expected LABEL=RESULTS.json" in capsys.readouterr().err
