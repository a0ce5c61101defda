"""Issue #79 item 3: guides apart from the study record. docs/ holds guides (what to run, what it
means, today's figures); docs/studies/ holds one dated record per study. Every record is named and
headed by its date, the index lists every record, the guides stay short and name no round, every
relative link of docs/ resolves, and the experiments guide's figures are their exports'."""

import glob
import os
import re
import shutil

from doc_pages import INDEX_BEGIN, INDEX_END, REPO, STUDIES, guide, index_rows, records_problems

GUIDE_MAX_LINES = 400  # [lines] a guide that grows past this is growing a record


def test_every_study_record_is_named_and_headed_by_its_date():
    assert records_problems() == []
    assert len(glob.glob(os.path.join(STUDIES, "????-??-??-*.md"))) >= 10


def test_a_record_without_its_date_or_record_line_is_named(tmp_path):
    good = sorted(glob.glob(os.path.join(STUDIES, "????-??-??-*.md")))[0]
    shutil.copy(good, tmp_path / "flaw-notes.md")  # no date in the name
    text = open(good, encoding="utf-8").read().split("\n")
    (tmp_path / "2026-01-02-moved.md").write_text("\n".join(text), encoding="utf-8")  # date not the record's
    (tmp_path / "2026-01-03-bare.md").write_text("# Bare\n\nno record line\n", encoding="utf-8")
    problems = records_problems(str(tmp_path))
    assert any(p.startswith("flaw-notes.md: not named") for p in problems), problems
    assert any(p.startswith("2026-01-02-moved.md: recorded") for p in problems), problems
    assert any(p.startswith("2026-01-03-bare.md: line 3") for p in problems), problems


def test_the_index_lists_every_record():
    page = open(os.path.join(STUDIES, "README.md"), encoding="utf-8").read()
    block = page.split(INDEX_BEGIN + "\n", 1)[1].split(INDEX_END, 1)[0]
    assert block.strip() == index_rows().strip(), "regenerate: python3 -m asg_analysis docs"


def test_the_guides_are_short_and_name_no_round():
    for name in ("experiments.md", "benchmarks.md"):
        lines = open(guide(name), encoding="utf-8").read().split("\n")
        assert (
            len(lines) <= GUIDE_MAX_LINES
        ), f"docs/{name}: {len(lines)} lines; a study's history goes to docs/studies/"
        rounds = [ln for ln in lines if ln.startswith("#") and re.search(r"\bRound \d", ln)]
        assert not rounds, f"docs/{name}: a heading names a round (a record's): {rounds}"


def test_the_guides_carry_no_issue_numbers_nor_a_round_as_a_default():
    """History (issue numbers, which round's default or winner a search was) belongs to the study
    records; a guide says what is, with a date where the when matters."""
    found = []
    for path in sorted(glob.glob(os.path.join(REPO, "docs", "*.md"))) + [os.path.join(REPO, "README.md")]:
        for n, line in enumerate(open(path, encoding="utf-8"), 1):
            if re.search(r"\bissues? #\d+|\b[Rr]ound \d+'s (default|winner|best)", line):
                found.append(f"{os.path.relpath(path, REPO)}:{n}: {line.strip()[:100]}")
    assert not found, "\n".join(found)


def test_every_relative_link_of_the_docs_resolves():
    broken = []
    pages = glob.glob(os.path.join(REPO, "docs", "**", "*.md"), recursive=True) + [os.path.join(REPO, "README.md")]
    for page in pages:
        text = open(page, encoding="utf-8").read()
        for target in re.findall(r"\]\(([^)\s]+)\)", text):
            if re.match(r"^(https?:|mailto:|#)", target):
                continue
            path = target.split("#", 1)[0]
            if not os.path.exists(os.path.join(os.path.dirname(page), path)):
                broken.append(f"{os.path.relpath(page, REPO)}: {target}")
    assert not broken, broken


def test_the_experiments_guide_figures_are_the_exports():
    """The "search today" block regenerates from protocol v4's confirmatory exports (every block run
    so far: one seed of each of the four arms), and the sentence under it quotes the row of round
    6's default with the fewest places."""
    from asg_agent.records.export import read_export
    from asg_analysis import endpoints

    paths = []
    for arm in ("default", "route-random", "random-own", "round6"):
        paths += sorted(glob.glob(os.path.join(REPO, "results", "distinct_v4", f"dist4-{arm}-s3?.jsonl.gz")))
    assert len(paths) >= 12 and len(paths) % 4 == 0, paths
    rows = sorted((endpoints.campaign(*read_export(p), budget=300) for p in paths), key=lambda c: c["campaign"])
    page = open(guide("experiments.md"), encoding="utf-8").read()
    block = page.split("<!-- search today: begin -->\n", 1)[1].split("<!-- search today: end -->", 1)[0]
    assert block.strip() == endpoints.markdown(rows).strip()
    old = min(
        (c for c in rows if c["campaign"].startswith("dist4-round6-")),
        key=lambda c: (c["distinct"]["2"], c["campaign"]),
    )
    seed = old["campaign"].rsplit("-s", 1)[1]
    said = f"seed {seed}: {old['findings']} flaw findings at {old['distinct']['2']} places 2 m apart"
    text = " ".join(page.split())
    assert said in text, said
    # "distinct flaw findings than route-random in every one of the five blocks, but fewer flaw modes"
    by = {c["campaign"]: c for c in rows}
    seeds = sorted(c["campaign"].rsplit("-s", 1)[1] for c in rows if c["campaign"].startswith("dist4-default-"))
    more = all(
        by[f"dist4-default-s{k}"]["distinct"]["2"] > by[f"dist4-route-random-s{k}"]["distinct"]["2"] for k in seeds
    )
    modes = [sum(by[f"dist4-{arm}-s{k}"]["modes"] for k in seeds) for arm in ("default", "route-random")]
    assert more and modes[0] < modes[1], (more, modes)
    assert len(seeds) == 5, seeds
    at = {
        w: [sum(by[f"dist4-{arm}-s{k}"]["distinct"][w] for k in seeds) for arm in ("default", "route-random")]
        for w in "25"
    }
    assert at["5"][0] < at["5"][1] and "and fewer distinct at 5 m" in text
    assert f"{at['2'][0] / at['2'][1]:.2f}x route-random at 2 m" in text
    assert "distinct flaw findings than route-random in every one of the five blocks, but fewer flaw modes" in text


def test_the_route_wide_files_say_which_layouts_are_not_reachable():
    # issue #78: u covers only the route outside the safety radii; exp1-route-wide.yaml said every
    # layout could be reached, and two other files pointed at a heading docs/agent.md does not have
    for path in glob.glob(os.path.join(REPO, "experiments", "*route-wide*.yaml")):
        text = " ".join(open(path, encoding="utf-8").read().split())
        assert "every layout of the scene can be reached" not in text, path
        assert '"Action spaces"' not in text, path
    exp1 = " ".join(open(os.path.join(REPO, "experiments", "exp1-route-wide.yaml"), encoding="utf-8").read().split())
    assert "Not every layout is reachable" in exp1
    assert "| `action_space` |" in open(os.path.join(REPO, "docs", "agent.md"), encoding="utf-8").read()
