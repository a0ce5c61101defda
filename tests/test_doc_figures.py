"""Issue #68: scripts/ci/doc_figures.py, the scan of the docs for figures with no test or
generated block beside them: its rule on a made-up page, and docs/testing.md's summary of it in
step with the pages."""

import os
import sys

REPO = os.path.abspath(os.path.join(os.path.dirname(os.path.realpath(__file__)), ".."))
sys.path.insert(0, os.path.join(REPO, "scripts", "ci"))
import doc_figures  # noqa: E402

FENCE = "`" * 3
PAGE = f"""# A made-up page

The made-up search found 318.4 findings an hour on the made-up stack.
The made-up loop drove 42.5 m before it stopped in the made-up meadow.
The made-up planner replanned every 2.5 s on the long meadow route of the page.
The made-up arm found 6.5 flaw findings in its made-up campaign of the page.
Names, not figures: issue #54, 2026-11-29, Debian 12, `--seeds 3`, round 3, 2-core, `run_7.yaml`,
and a code span over two lines: `tool --at
47.25 0.05`.

<!-- widgets:begin (generated) -->
| widgets | 12.25 |
<!-- widgets:end -->

<!-- gizmo table -->
| gizmos | 3.75 % |
<!-- end gizmo table -->

{FENCE}text
timing 99.125 ms
{FENCE}

    indented 77.5 ms

## widget node

| parameter | unit | default |
|---|---|---|
| `rate` | Hz | 17.5 |
"""

CHECK = """import os

DOC = os.path.join("docs", "page.md")
SECTION = "## widget node"


def test_it():
    assert 318.4 > 0
    said = (
        "The made-up planner replanned every "
        "2.5 s on the long meadow route"
    )
    x = 6.5
    assert f"The made-up arm found {x:.1f} flaw findings in its made-up campaign" in open(DOC).read()
"""


def made_up(tmp_path):
    (tmp_path / "docs").mkdir()
    (tmp_path / "tests").mkdir()
    (tmp_path / "docs" / "page.md").write_text(PAGE, encoding="utf-8")
    (tmp_path / "docs" / "other.md").write_text("Elsewhere the made-up search found 318.4 findings.\n")
    (tmp_path / "tests" / "test_page.py").write_text(CHECK, encoding="utf-8")
    return doc_figures.scan(str(tmp_path))


def test_the_rule_on_a_made_up_page(tmp_path):
    result = made_up(tmp_path)
    page = {f["figure"]: (f["kind"], f["rule"]) for f in result[os.path.join("docs", "page.md")]}
    assert page == {
        "318.4 findings": ("checked", "a"),  # the test names the page and holds the number
        "42.5 m": ("left", None),  # nothing holds it
        "2.5 s": ("checked", "b"),  # a test holds the sentence (two literals, one string)
        "6.5": ("checked", "c"),  # a test fills the sentence from its own value
        "12.25": ("generated", None),  # between NAME:begin and NAME:end
        "3.75 %": ("generated", None),  # between <!-- NAME --> and <!-- end NAME -->
    }, page  # no names, no code (spans, fenced or indented), no parameter table a test holds whole
    other = result[os.path.join("docs", "other.md")]
    assert [(f["figure"], f["kind"]) for f in other] == [("318.4 findings", "left")], "no test names other.md"
    counts = doc_figures.counts(result[os.path.join("docs", "page.md")])
    assert counts == (6, 3, 2, 1)
    assert "| docs/page.md | 6 | 3 | 2 | 1 |" in doc_figures.summary(result)
    assert "    4  The made-up loop drove 42.5 m" in doc_figures.markdown(result)


def test_the_block_is_rewritten_and_checked(tmp_path):
    made_up(tmp_path)
    doc = tmp_path / "docs" / "testing.md"
    doc.write_text(f"# Testing\n\nbefore\n\n{doc_figures.BEGIN}\nold\n{doc_figures.END}\n\nafter\n")
    argv = ["--repo", str(tmp_path), "--doc", str(doc)]
    assert doc_figures.main(argv + ["--check"]) == 1
    assert doc_figures.main(argv) == 0
    assert doc_figures.main(argv + ["--check"]) == 0
    text = doc.read_text()
    assert text.startswith("# Testing\n\nbefore\n\n") and text.endswith("\n\nafter\n")
    assert "| docs/page.md | 6 | 3 | 2 | 1 |" in text
    assert "| docs/testing.md | 0 | 0 | 0 | 0 |" in text, "the block itself is not read"
    doc.write_text("# Testing\n")
    assert doc_figures.main(argv + ["--check"]) == 2


def test_the_block_of_docs_testing_md_is_in_step_with_the_pages():
    doc = os.path.join(REPO, "docs", "testing.md")
    assert (
        doc_figures.main(["--doc", doc, "--check"]) == 0
    ), "docs/testing.md's doc figures block is stale: run python3 scripts/ci/doc_figures.py --doc docs/testing.md"


def test_the_rostest_repeat_block_is_the_records():
    # docs/testing.md's table of the repeated rostests (issue #68 item 4) is generated from the record
    import subprocess

    r = subprocess.run(
        [
            "/usr/bin/python3",
            os.path.join(REPO, "scripts", "ci", "repeat_summary.py"),
            os.path.join("results", "flaky", "r6-goalclient-repeat.txt"),
            os.path.join("results", "flaky", "r6-campaign-faults-repeat.txt"),
            os.path.join("results", "flaky", "r6-sound-runs-repeat.txt"),
            "--doc",
            os.path.join(REPO, "docs", "testing.md"),
            "--check",
        ],
        capture_output=True,
        text=True,
        cwd=REPO,
    )
    assert r.returncode == 0, r.stderr
    text = open(os.path.join(REPO, "docs", "testing.md"), encoding="utf-8").read()
    rows = [
        ln
        for ln in text.split("<!-- rostest repeat: begin")[1].split("<!-- rostest repeat: end")[0].splitlines()
        if ln.startswith("| `")
    ]
    assert rows and all(int(r.split("|")[2]) >= 20 for r in rows), "each test ran 20 times in a row"
    assert [r.split("|")[1].strip() for r in rows] == [
        "`stack_faults.test`",
        "`campaign_faults.test`",
        "`sound_runs.test`",
    ]
    sound = [
        ln.split() for ln in open(os.path.join(REPO, "results", "flaky", "r6-sound-runs-repeat.txt")) if ln[0] != "#"
    ]
    prose = " ".join(text.split())
    import statistics

    med = statistics.median(float(r[6]) for r in sound)
    assert f"{sum(r[2] == 'PASS' for r in sound)} of {len(sound)} passed, a median {med:.1f} s a run" in prose
    first = [
        ln.split()
        for ln in open(os.path.join(REPO, "results", "flaky", "r6-sound-runs-repeat-75eba8c.txt"))
        if ln[0] != "#"
    ]
    assert [r[2] for r in first] == ["PASS", "FAIL", "PASS"] and "stopped after 3 runs). In run 2, test_7" in prose
