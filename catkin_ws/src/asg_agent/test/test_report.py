"""analysis.report: what a campaign's HTML report says of a stack other than the paper's (issue #55)."""

import os

from asg_agent.analysis import report

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", "..", ".."))


def test_a_registered_stack_finds_the_baseline_of_its_scenario_and_names_its_reference():
    exp = os.path.join(REPO, "experiments", "exp1-depth.yaml")
    # exp1-depth runs exp1's layouts: its baseline row (depth) is in exp1.json
    assert report.baseline_path("exp1-depth", {"experiment_file": exp}) == os.path.join(
        REPO, "results", "baseline", "exp1.json"
    )
    html = report._baseline_html("exp1-depth", {"experiment_file": exp})
    assert "<td>depth</td>" in html and "No baseline" not in html
    assert report.baseline_path("nowhere", {}) == ""
    assert "No baseline of nowhere yet" in report._baseline_html("nowhere", {})
    # the single reference is the paper's stack on ground truth: not the depth stack's planner
    assert "the same planner" in report.reference_words({"stack": "paper"})
    assert "another planner and follower than depth's" in report.reference_words({"stack": "depth"})
