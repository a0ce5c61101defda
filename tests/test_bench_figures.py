"""docs/benchmarks.md's before/after figures of issue #38's refactor (results/bench/r4-arch-*) and
of issue #56's architecture step (results/bench/r5-arch-*, the same bench), recomputed from the
committed stage reports and result digests."""

import glob
import json
import os

import pytest

from asg_analysis.bench import before_after, before_after_sentence

REPO = os.path.abspath(os.path.join(os.path.dirname(os.path.realpath(__file__)), ".."))


@pytest.mark.parametrize("tag", ["r4-arch", "r5-arch"])
def test_the_refactor_bench_in_the_docs_is_its_reports(tag):
    TAG = os.path.join(REPO, "results", "bench", tag)
    before = sorted(glob.glob(TAG + "-before-*.json"))
    after = sorted(glob.glob(TAG + "-after-*.json"))
    assert len(before) == len(after) == 3

    def load(paths):
        return [json.load(open(p)) for p in paths]

    sentence = before_after_sentence(before_after(load(before), load(after)))
    with open(os.path.join(REPO, "docs", "benchmarks.md")) as f:
        assert sentence in " ".join(f.read().split()), sentence
    # every campaign, on either side, found the same 120 results (requests, outcomes, trajectories)
    digests = {open(p[: -len(".json")] + ".digest").read().strip() for p in before + after}
    assert len(digests) == 1 and next(iter(digests)).startswith("120 "), digests
