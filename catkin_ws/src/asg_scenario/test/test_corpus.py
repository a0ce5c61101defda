"""The shared corpus of scenario files (scenarios/corpus): this validator judges it as the C++
one does (asg_sim's gtest Scene.SharedCorpus reads the same files). A bad file's first line says
which field it breaks: `# expect: FIELD`; the validator must reject it naming that field."""

import glob
import os
import time

import pytest

from asg_scenario import ScenarioError, load_scenario

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", "..", ".."))
CORPUS = os.path.join(REPO, "scenarios", "corpus")
GOOD = sorted(glob.glob(os.path.join(CORPUS, "good", "*.yaml"))) + sorted(
    glob.glob(os.path.join(REPO, "scenarios", "*.yaml"))
)
BAD = sorted(glob.glob(os.path.join(CORPUS, "bad", "*.yaml")))


def expected_field(path):
    with open(path, encoding="utf-8") as f:
        first = f.readline()
    assert first.startswith("# expect: "), f"{path}: first line must be '# expect: FIELD'"
    return first[len("# expect: ") :].strip()


def test_corpus_size():
    assert len(BAD) >= 30 and len(GOOD) >= 6
    assert len({expected_field(p) + os.path.basename(p) for p in BAD}) == len(BAD)


@pytest.mark.parametrize("path", GOOD, ids=os.path.basename)
def test_good_files_load(path):
    load_scenario(path)


@pytest.mark.parametrize("path", BAD, ids=os.path.basename)
def test_bad_files_rejected_naming_the_field(path):
    field = expected_field(path)
    t0 = time.perf_counter()
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    assert time.perf_counter() - t0 < 1.0  # oversized scenes are refused, not built
    assert field in [p for p, _ in info.value.problems], str(info.value)
