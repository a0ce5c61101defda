"""asg_analysis.study (issue #80 item 1): a protocol's `report:` list regenerates its record's
blocks with one command, `--check` tells a stale block, and a bad entry is named."""

import glob
import os
import re

import pytest
import yaml

from asg_analysis import endpoints, study
from asg_agent.records.export import read_export

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", "..", ".."))
PILOT = os.path.join(REPO, "results", "distinct_v4", "dist4-pilot-ops-wide-s2*.jsonl.gz")


def _study(tmp_path, entries):
    page = tmp_path / "record.md"
    page.write_text("# r\n\n<!-- one: begin -->\nold\n<!-- one: end -->\n\n<!-- two: begin -->\n<!-- two: end -->\n")
    proto = tmp_path / "protocol.yaml"
    proto.write_text(yaml.safe_dump({"name": "x", "report": [dict(e, page=str(page)) for e in entries]}))
    return page, proto


def test_the_runner_writes_and_checks_each_block(tmp_path, capsys):
    page, proto = _study(
        tmp_path,
        [
            {"block": "one", "table": "campaigns", "exports": PILOT, "budget": 150},
            {"block": "two", "table": "arms", "arms": {"default": PILOT, "none": str(tmp_path / "no-*.jsonl.gz")}},
        ],
    )
    assert study.run([str(proto), "--check"]) == 1  # block one is stale ("old")
    assert "block 'one' is stale" in capsys.readouterr().out
    assert study.run([str(proto)]) == 0
    out = capsys.readouterr().out
    assert "block 'one' written" in out and "two: skipped, no export of arm(s) none" in out
    want = endpoints.markdown([endpoints.campaign(*read_export(p), budget=150) for p in sorted(glob.glob(PILOT))])
    assert study.block_text(str(page), "one").strip() == want.strip()
    assert study.run([str(proto), "--check"]) == 0


def test_a_bad_entry_or_a_protocol_without_report_is_named(tmp_path, capsys):
    _, proto = _study(tmp_path, [{"block": "one", "table": "pie", "exports": PILOT}])
    assert study.run([str(proto)]) == 2
    assert "table 'pie' must be one of campaigns, arms, rules, digests, coverage, command" in capsys.readouterr().err
    bare = tmp_path / "bare.yaml"
    bare.write_text("name: x\n")
    assert study.run([str(bare)]) == 2
    assert "no `report:` list" in capsys.readouterr().err


def test_the_v4_record_is_what_its_protocols_generate():
    for name in ("distinct-v4", "distinct-v4-exp3", "distinct-v4-exp6", "distinct-v4-gapnav", "distinct-v4-depth"):
        assert (
            study.regenerate(
                os.path.join(REPO, "experiments", f"protocol-{name}.yaml"), check=True, out=open(os.devnull, "w")
            )
            == 0
        ), name


def test_a_command_entry_runs_its_generator_and_checks_it(tmp_path, capsys):
    from asg_analysis import replays

    folder = os.path.join(REPO, "results", "flaw_study")
    begin, end = replays.markers(folder)
    page = tmp_path / "record.md"
    page.write_text(f"# r\n\n{begin}\nold\n{end}\n")
    proto = tmp_path / "protocol.yaml"
    entry = {"table": "command", "command": "replays", "args": [folder, "--doc", str(page)]}
    proto.write_text(yaml.safe_dump({"name": "x", "report": [entry]}))
    assert study.run([str(proto), "--check"]) == 1 and "stale" in capsys.readouterr().out
    assert page.read_text().count("old") == 1  # --check wrote nothing
    assert study.run([str(proto)]) == 0
    assert replays.markdown(replays.read(folder)) in page.read_text()
    assert study.run([str(proto), "--check"]) == 0


def test_every_study_with_a_record_lists_its_blocks():
    """A new study is a protocol file: each protocol whose study has a record under docs/studies/
    names that record's generated blocks in its `report:` list."""
    records = " ".join(
        open(p, encoding="utf-8").read() for p in glob.glob(os.path.join(REPO, "docs", "studies", "*.md"))
    )
    for path in sorted(glob.glob(os.path.join(REPO, "experiments", "protocol-*.yaml"))):
        name = os.path.basename(path)
        if name not in records:
            continue  # a protocol no record names
        with open(path, encoding="utf-8") as f:
            p = yaml.safe_load(f)
        if name in (
            "protocol-round4.yaml",
            "protocol-design-loop.yaml",
            "protocol-regression-depth-rc2.yaml",
            "protocol-regression-depth-rc3.yaml",
        ):
            continue
        assert p.get("report"), f"{name}: its record's blocks are not listed (report:)"


def test_the_rules_table_shows_the_learnt_rules_and_the_first_ones_check(tmp_path):
    from asg_analysis import rules
    from asg_analysis.exports import read_rows

    d4 = os.path.join(REPO, "results", "distinct_v4")
    entry = {
        "block": "r",
        "table": "rules",
        "rules": "results/distinct_v4/rules-ops-wide.json",
        "exports": "results/distinct_v4/dist4-rule-top-s40.jsonl.gz",
        "base": "results/distinct_v4/dist4-random-own-s3?.jsonl.gz",
    }
    text = study.render(entry)
    fresh = read_rows([os.path.join(d4, "dist4-rule-top-s40.jsonl.gz")], "", "")[0]
    base = read_rows(sorted(glob.glob(os.path.join(d4, "dist4-random-own-s3?.jsonl.gz"))), "", "")[0]
    c = rules.check(fresh, base, "flaw")
    first, second = text.splitlines()[2:4]
    assert first.startswith("| `barberry d<2m q3 >= 3` |")
    assert f"{c['rule_findings']} / {c['rule_scenarios']}" in first and f"{c['fisher_p']:.3f}" in first
    assert "not checked" in second and "not checked" not in first
    # without the fresh samples the first rule is not checked either
    assert "not checked" in study.render(dict(entry, exports="results/distinct_v4/none-*.jsonl.gz")).splitlines()[2]


MARKER = re.compile(r"<!-- ([^:>]+?) ?: ?begin")


def _named_blocks():
    """Every block a study file names: `block:` of a table entry, `blocks:` of a command entry."""
    names = set()
    for path in glob.glob(os.path.join(REPO, "experiments", "*.yaml")):
        with open(path, encoding="utf-8") as f:
            for e in (yaml.safe_load(f) or {}).get("report") or []:
                names.update([e["block"]] if "block" in e else e.get("blocks", []))
    return names


def unnamed_blocks(pages, names, tests_text):
    """The generated blocks of `pages` ({path: text}) that no study file names and no test quotes."""
    out = []
    for path, text in sorted(pages.items()):
        for name in MARKER.findall(text):
            if name not in names and f"<!-- {name}: begin" not in tests_text:
                out.append(f"{os.path.basename(path)}: {name}")
    return out


def test_every_generated_block_of_every_record_is_named_by_a_study_file():
    """Issue #80: each record regenerates from its study file (protocol-*.yaml, or study-*.yaml for
    a record older than protocols) with `python3 -m asg_analysis study FILE`; a block no file names
    is one sentence a test quotes and checks (the v3 pilot's choice) or it fails here."""
    pages = {p: open(p, encoding="utf-8").read() for p in glob.glob(os.path.join(REPO, "docs", "studies", "2*.md"))}
    tests_text = " ".join(open(p, encoding="utf-8").read() for p in glob.glob(os.path.join(REPO, "tests", "test_*.py")))
    names = _named_blocks()
    assert unnamed_blocks(pages, names, tests_text) == []
    assert len([n for t in pages.values() for n in MARKER.findall(t)]) >= 20
    # a block added to a record and named by no study file is found (the mutation)
    pages["x.md"] = "<!-- new table: begin -->\n<!-- new table: end -->\n"
    assert unnamed_blocks(pages, names, tests_text) == ["x.md: new table"]


def test_the_refactors_and_round3_records_are_what_their_study_files_generate():
    for name in ("study-refactors", "study-round3-search-comparison"):
        assert (
            study.regenerate(os.path.join(REPO, "experiments", f"{name}.yaml"), check=True, out=open(os.devnull, "w"))
            == 0
        )


def test_the_digests_table_quotes_each_file(tmp_path):
    d = tmp_path / "a.digest"
    d.write_text("120 0e0d360e6744453582c881296539cd8148258ccd4d60695b9713ba6403f30068\n")
    text = study.render({"block": "b", "table": "digests", "digests": {"before (x)": str(d)}})
    assert text == f"- before (x): `{d}`, 120 results, 0e0d360e\n"


def test_exports_of_one_experiment_may_differ_in_its_comments_only(tmp_path):
    """read_rows takes campaigns whose stored experiment files differ in comments alone (a header
    reworded between two blocks of a study) and refuses one whose keys differ."""
    import gzip
    import json

    from asg_analysis.exports import read_rows

    def export(name, text):
        path = tmp_path / f"{name}.jsonl.gz"
        with gzip.open(path, "wt") as f:
            f.write(json.dumps({"campaign": {"name": name, "experiment_text": text}}) + "\n")
            f.write(json.dumps({"job": 0, "termination": "SUCCESS"}) + "\n")
        return str(path)

    a = export("a", "# the old header\nname: e\nsim_timeout: 60.0\n")
    b = export("b", "# the new header,\n# two lines\nname: e\nsim_timeout: 60.0\n")
    c = export("c", "# the old header\nname: e\nsim_timeout: 30.0\n")
    rows, camp = read_rows([a, b])
    assert [r["_campaign"] for r in rows] == ["a", "b"] and camp["name"] == "a"
    with pytest.raises(ValueError, match="another experiment than"):
        read_rows([a, c])
