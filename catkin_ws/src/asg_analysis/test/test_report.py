"""analysis.report: what a campaign's HTML report says of a stack other than the paper's (issue #55)."""

import os
import sys

AGENT_TEST = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "asg_agent", "test")
sys.path.insert(0, AGENT_TEST)  # the agent's stand-in campaigns, built as its own tests build them

from asg_analysis import report  # noqa: E402

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", "..", ".."))


def test_a_registered_stack_finds_the_baseline_of_its_scenario_and_names_its_reference():
    exp = os.path.join(REPO, "experiments", "exp1-depth.yaml")
    # exp1-depth runs exp1's layouts: its baseline row (depth) is in exp1.json
    assert report.baseline_path("exp1-depth", {"experiment_file": exp}) == os.path.join(
        REPO, "results", "baseline", "exp1.json"
    )
    # issue #68: recorded repository-relative (resolved against the repository's root, from any
    # folder), or absolute on another machine beside the repository-relative one
    for recorded in (
        {"experiment_file": "experiments/exp1-depth.yaml"},
        {
            "experiment_file": "/elsewhere/experiments/exp1-depth.yaml",
            "experiment_repo_file": "experiments/exp1-depth.yaml",
        },
    ):
        assert report.baseline_path("exp1-depth", recorded) == os.path.join(REPO, "results", "baseline", "exp1.json")
    html = report._baseline_html("exp1-depth", {"experiment_file": exp})
    assert "<td>depth</td>" in html and "No baseline" not in html
    assert report.baseline_path("nowhere", {}) == ""
    assert "No baseline of nowhere yet" in report._baseline_html("nowhere", {})
    # the single reference is the paper's stack on ground truth: not the depth stack's planner
    assert "the same planner" in report.reference_words({"stack": "paper"})
    assert "another planner and follower than depth's" in report.reference_words({"stack": "depth"})


def test_the_report_of_a_store_that_is_not_there_says_so_and_makes_none(tmp_path, capsys):
    missing = tmp_path / "typo.sqlite"
    assert report.run(["campaign", str(missing), "c", str(tmp_path / "out")]) == 2
    assert "no such scenario store" in capsys.readouterr().err
    assert not missing.exists()


def test_the_report_shows_the_three_stack_classes(tmp_path):
    from test_attribution import WANT, three_stack

    c, store, _ = three_stack(tmp_path, "e")
    c.start()
    c.run(poll_timeout=0.0)
    page = open(report.campaign_report(store.path, "e", str(tmp_path / "report"))).read()
    assert "Three-stack attribution" in page and "4 of 24 scenarios were candidates" in page
    assert page.count("quarter of the route") == len(WANT)  # each finding with its failure mode
    for job in WANT:  # each finding with its three paths and its replay command
        assert f"three_job{job}.png" in page and os.path.isfile(tmp_path / "report" / f"three_job{job}.png")
        assert f"replay {store.path} e {job}" in page


def test_the_report_agrees_with_the_store(tmp_path):
    from stand_ins import campaign

    from stand_in.fake_pool import FakePool

    c = campaign(tmp_path, "rep", FakePool(2, seed=8), total=30, method="random")
    c.start()
    c.run()
    s = c.store.summary("rep")
    page = open(report.campaign_report(c.store.path, "rep", str(tmp_path / "report"), top=3)).read()
    assert f"<td>{s['scenarios']}</td><td>{s['proxy_ge_3']}</td><td>{s['proxy_ge_4']}</td>" in page
    # issue #78: what it searched for comes first, its best distinct findings each with its replay
    from asg_agent.campaign.findings import distinct_summary, findings

    d = distinct_summary(findings(c.store, "rep"))
    assert page.index("<h2>What it found</h2>") < page.index("<h2>Counts")
    assert f"<b>{d['findings']}</b> findings of the proxy reward" in page
    assert f"<b>{d['distinct'][2.0]}</b> at 2 m" in page
    assert page.count("rosrun asg_agent replay") == 3 + min(3, len(d["first_at_each_place"]))
    assert os.path.isfile(tmp_path / "report" / "curves.png")


def test_the_figure_command_draws_the_jobs_named_and_names_a_missing_one(tmp_path, capsys):
    from stand_ins import campaign

    from stand_in.fake_pool import FakePool
    from asg_analysis import figures

    c = campaign(tmp_path, "fig", FakePool(2, seed=8), total=6, method="random")
    c.start()
    c.run()
    out = tmp_path / "pics"
    assert figures.run([c.store.path, "fig", "--job", "2", "--job", "4", "--out", str(out)]) == 0
    assert sorted(os.listdir(out)) == ["fig_job2.png", "fig_job4.png"]
    assert figures.run([c.store.path, "fig", "--job", "99", "--out", str(out)]) == 2
    assert "campaign 'fig' has no job 99" in capsys.readouterr().err
