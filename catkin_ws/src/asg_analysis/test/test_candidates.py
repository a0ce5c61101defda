"""asg_analysis.studies.candidates: the check of the candidate rule against full re-runs."""


def test_the_candidate_check_counts_what_the_rule_missed():
    from asg_analysis.studies.candidates import check

    rows = [
        {"job": 0, "termination": "COLLISION", "proxy": 0.8, "attribution": "flaw"},
        {"job": 1, "termination": "SUCCESS", "proxy": 1.1, "attribution": "not_candidate"},
        {"job": 2, "termination": "SUCCESS", "proxy": 1.2, "attribution": "not_candidate"},
        {"job": 3, "termination": "SUCCESS", "proxy": 2.4, "attribution": "pass"},
    ]
    ok, hit = {"termination": "SUCCESS", "proxy": 1.0}, {"termination": "COLLISION", "proxy": 0.5}
    full = {0: ok, 1: ok, 2: hit, 3: ok}
    truth = {0: ok, 1: ok, 2: ok, 3: hit}  # job 3: the campaign stored the wrong class
    out = check(rows, full, truth)
    assert (out["scenarios"], out["candidates"], out["candidates_same_class"]) == (4, 2, 1)
    assert out["candidates_differing"] == [{"job": 3, "stored": "pass", "rerun": "reverse"}]
    assert out["missed_findings"] == [] and out["missed_reverse"] == [2]
    assert out["not_candidates"]["pass"] == 1 and out["not_candidates"]["reverse"] == 1
