"""Issue #68 item 9: sentences of docs/design-loop.md held to what was measured: what the campaigns
decided about the suites' arms, which models the frames before the contacts cover, and what the
interruptions the generated table lists as pauses were."""

import gzip
import json
import math
import os
import re

REPO = os.path.abspath(os.path.join(os.path.dirname(os.path.realpath(__file__)), ".."))
HARD = os.path.join(REPO, "results", "hardening")


def page():
    with open(os.path.join(REPO, "docs", "design-loop.md"), encoding="utf-8") as f:
        return f.read()


def loop():
    with open(os.path.join(HARD, "loop.json"), encoding="utf-8") as f:
        return json.load(f)


def bullet(text, head):
    """The list item that starts with **head**, whitespace collapsed."""
    m = re.search(rf"^- \*\*{re.escape(head)}.*?(?=^- |^\S|\Z)", text, re.S | re.M)
    assert m, head
    return " ".join(m.group().split())


def test_the_suites_bullet_says_what_the_campaigns_decided():
    from scipy.stats import fisher_exact

    # the pooled test of section 4, from the figures its table uses (as test_design_loop_figures.py)
    arms = {r["arm"]: r for r in loop()["compare"]}
    found = [sum(round(c * 500 / 1000) for c in arms[a]["counts"]) for a in ("hardened-findings", "hardened-random")]
    n = 1500
    p = fisher_exact([[found[0], n - found[0]], [found[1], n - found[1]]]).pvalue
    said = bullet(page(), "The suites do not separate the arms.")
    open_ = "did not separate the arms either: pooled over seeds, Fisher's exact test leaves it open"
    if p >= 0.05:  # the campaigns decided nothing either, and the page says so
        assert open_ in said and "the campaigns below do" not in said, (p, said)
    else:
        assert open_ not in said, p
    # what the bullet says of the trained findings: the random arm passes the same ones, and no reason
    import yaml

    from asg_agent.campaign.suite import verdict

    with open(os.path.join(HARD, "suite-exp1c", "suite.yaml"), encoding="utf-8") as f:
        suite = yaml.safe_load(f)

    def passed(label):
        return {
            e["job"]
            for e in suite["scenarios"]
            if not verdict(e["outcomes"][label]["termination"], e["outcomes"][label].get("proxy"), suite["bound"])[0]
        }

    assert passed("hardened-findings-1") == passed("hardened-random-1")
    assert "the random arm passes the same ones; why was not measured" in said
    assert "tree blindness" not in page() and "any scene with a juniper teaches" not in page()


def test_the_frames_before_the_contacts_are_said_to_cover_the_models_they_cover():
    with open(os.path.join(HARD, "mechanism", "mechanism.json"), encoding="utf-8") as f:
        models = list(json.load(f)["models"])
    assert not any(m.startswith("flawed_h") for m in models)  # no hardened model labelled them
    names = " and ".join(f"`{m}`" for m in models)
    said = bullet(page(), "Most of the gain is one both arms get")
    assert "why was not measured" in said
    assert f"were labelled by {names} only, not by the hardened models" in said, said
    assert "show why" not in said


def test_the_listed_pauses_are_called_what_they_were():
    text = page()
    listed = [
        (name, int(re.search(r"after job (\d+)$", e).group(1)), e)
        for name, c in loop()["campaigns"].items()
        for e in c["interruptions"]
        if e.startswith("paused ")
    ]
    assert len(listed) == 2  # "Both listed pauses"
    flat = " ".join(re.sub(r"<!-- loop table -->.*?<!-- end loop table -->", " ", text, flags=re.S).split())
    for name, job, e in listed:
        with gzip.open(os.path.join(HARD, f"{name}.jsonl.gz"), "rt") as f:
            head = json.loads(f.readline())["campaign"]
            settings = head["settings"] if isinstance(head["settings"], dict) else json.loads(head["settings"])
            rows = [json.loads(ln) for ln in f]
        # no event recorded it: the export's settings hold none (the store did not record them yet)
        assert not settings.get("events"), name
        # one campaign, every job once, and the jobs finished before the gap kept in it
        jobs = [r["job"] for r in rows]
        assert sorted(jobs) == list(range(settings["total"])), name
        fin = sorted((r["finished"], r["job"]) for r in rows)
        gap = next(i for i, (a, b) in enumerate(zip(fin, fin[1:])) if a[1] == job and b[0] - a[0] > 600)
        assert gap > 0 and math.isclose(fin[gap + 1][0] - fin[gap][0], float(e.split()[1].replace(",", "")), abs_tol=1)
        assert re.search(rf"`{re.escape(name)}` was (parked|stopped) after job {job} and resumed", flat), name
    assert "Both listed pauses were resumes: each campaign was stopped and resumed with the jobs it had" in flat
    assert "finished kept (they are in its export, before the gap)" in flat
