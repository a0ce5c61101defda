"""Where the docs keep each generated block (issue #79: guides in docs/, dated study records in
docs/studies/). A test that checks a figure names the page that holds it through `record`, so that a
record renamed or lost fails the test that reads it, naming what is missing."""

import glob
import os
import re

from asg_analysis.docs import RECORD_LINE  # noqa: F401 (the index itself: python3 -m asg_analysis docs)
from asg_analysis.docs import records_index as index_rows  # noqa: F401

REPO = os.path.dirname(os.path.dirname(os.path.realpath(__file__)))
STUDIES = os.path.join(REPO, "docs", "studies")


def record(slug: str) -> str:
    """The path of the one study record docs/studies/DATE-SLUG.md."""
    found = sorted(glob.glob(os.path.join(STUDIES, f"????-??-??-{slug}.md")))
    assert len(found) == 1, f"docs/studies/: {len(found)} records named DATE-{slug}.md, expected one"
    return found[0]


def guide(name: str) -> str:
    """The path of a guide, docs/NAME."""
    return os.path.join(REPO, "docs", name)


INDEX_BEGIN, INDEX_END = "<!-- records: begin -->", "<!-- records: end -->"


def records_problems(root: str = STUDIES) -> list:
    """What is wrong with the study records under `root`: a name without its date, a first line that
    is no title, a third line that is not the record line, or a date that is not the name's."""
    out = []
    for p in sorted(glob.glob(os.path.join(root, "*.md"))):
        name = os.path.basename(p)
        if name == "README.md":
            continue
        m = re.match(r"^(\d{4}-\d{2}-\d{2})-[a-z0-9-]+\.md$", name)
        lines = open(p, encoding="utf-8").read().split("\n")
        if not m:
            out.append(f"{name}: not named DATE-SLUG.md")
            continue
        if not lines[0].startswith("# "):
            out.append(f"{name}: the first line is not its title")
        rec = RECORD_LINE.match(lines[2] if len(lines) > 2 else "")
        if not rec:
            out.append(f"{name}: line 3 is not '*Study record, DATE (issue #N). Status: ...'")
        elif rec.group(1) != m.group(1):
            out.append(f"{name}: recorded {rec.group(1)}, named {m.group(1)}")
    return out
