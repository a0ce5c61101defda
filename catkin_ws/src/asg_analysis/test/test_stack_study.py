"""analysis.stack_study: the search against random on one stack, one seed an arm (issue #39)."""

import gzip
import json

import pytest

from asg_analysis.studies import stack_study


def export(path, name, outcomes):
    with gzip.open(path, "wt", encoding="utf-8") as f:
        f.write(json.dumps({"campaign": {"name": name}}) + "\n")
        for job, (term, proxy) in enumerate(outcomes):
            f.write(json.dumps({"job": job, "termination": term, "proxy": proxy}) + "\n")


def test_counts_failures_with_exact_intervals_and_tests_the_arms(tmp_path):
    search = [("SUCCESS", 1.0 + 0.001 * k) for k in range(95)] + [("COLLISION", 1.2)] * 3 + [("SUCCESS", 3.5)] * 2
    random = [("SUCCESS", 1.0)] * 99 + [("ERROR", None)]
    export(tmp_path / "s.jsonl.gz", "s", search)
    export(tmp_path / "r.jsonl.gz", "r", random)
    out = tmp_path / "c.json"
    assert stack_study.run([str(tmp_path), "s", "r", "--json", str(out)]) == 0
    s = json.loads(out.read_text())
    a, b = s["arms"]["s"], s["arms"]["r"]
    assert (a["failures"], a["scenarios"], a["errors"]) == (5, 100, 0)
    assert a["failure_jobs"] == [95, 96, 97, 98, 99]
    assert a["per_1000"] == pytest.approx(50.0)
    lo, hi = a["per_1000_interval"]
    assert lo == pytest.approx(16.4, abs=0.1) and hi == pytest.approx(112.8, abs=0.1)  # Clopper-Pearson 5/100
    # An ERROR run is no outcome: not a failure, not in the denominator.
    assert (b["failures"], b["errors"], b["per_1000"]) == (0, 1, 0.0)
    assert b["per_1000_interval"][0] == 0.0 and b["per_1000_interval"][1] == pytest.approx(36.6, abs=0.1)
    assert s["fisher_p"] == pytest.approx(0.0594, abs=1e-3)
    assert s["proxy_mann_whitney"]["effect"] > 0.9  # the search's proxies sit above random's
    assert a["proxy_ge_candidate"] == 2 and a["terminations"] == {"COLLISION": 3, "SUCCESS": 97}
    md = stack_study.markdown(s)
    assert "| s | 100 | 5 | 50.0 (16.4-112.8) |" in md and "Fisher's exact test" in md


def test_a_missing_export_is_named(tmp_path, capsys):
    assert stack_study.run([str(tmp_path), "s", "r"]) == 2
    assert "s.jsonl.gz: no export" in capsys.readouterr().err


def test_several_seeds_an_arm_compare_the_per_seed_rates(tmp_path, capsys):
    for seed, k in enumerate((5, 8, 3)):  # the search: k failures in 100
        export(
            tmp_path / f"x-search-s{seed}.jsonl.gz", "s", [("SUCCESS", 1.1)] * (100 - k) + [("IDLING_TIMEOUT", 1.0)] * k
        )
    for seed, k in enumerate((0, 1, 0)):
        export(tmp_path / f"x-random-s{seed}.jsonl.gz", "r", [("SUCCESS", 1.0)] * (100 - k) + [("COLLISION", 1.2)] * k)
    searches = ",".join(f"x-search-s{i}" for i in range(3))
    randoms = ",".join(f"x-random-s{i}" for i in range(3))
    out = tmp_path / "seeds.json"
    assert stack_study.run([str(tmp_path), searches, randoms, "--json", str(out)]) == 0
    s = json.loads(out.read_text())
    assert (s["search"], s["baseline"]) == ("x-search", "x-random")
    assert [s["campaigns"][f"x-search-s{i}"]["failures"] for i in range(3)] == [5, 8, 3]
    head, other = s["compare"]
    assert head["arm"] == "x-search" and head["counts"] == [50.0, 80.0, 30.0]
    assert head["mean"] == pytest.approx(160 / 3) and head["lo"] <= head["mean"] <= head["hi"]
    # 3 against 3, with ties: the normal approximation (no exact p with ties)
    # exact with ties (issue #67): every search seed above every random one, 2 of the 20 splits
    assert other["counts"] == [0.0, 10.0, 0.0] and other["p"] == pytest.approx(2 / 20)
    assert s["pooled"] == [[16, 284], [1, 299]] and s["pooled_fisher_p"] < 1e-3
    md = stack_study.markdown_seeds(s)
    assert "| x-search-s1 | 100 | 8 | 80.0 (" in md and "Pooled over the seeds: 16 failures in 300" in md
    # a name given twice, or both arms with one stem, is refused by name (issue #68: the second case
    # named x-search-s2 twice, so the duplicate check refused it and the stem check never ran)
    capsys.readouterr()
    assert stack_study.run([str(tmp_path), "x-search-s0,x-search-s0", randoms]) == 2
    assert "a campaign is named twice" in capsys.readouterr().err
    assert stack_study.run([str(tmp_path), "x-search-s0,x-search-s1", "x-search-s2"]) == 2
    err = capsys.readouterr().err
    assert "the search's and the baseline's campaigns share a name: ['x-search']" in err, err
