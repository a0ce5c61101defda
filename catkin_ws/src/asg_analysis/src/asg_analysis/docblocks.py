"""The one writer of docs/'s generated blocks (no ROS): every study, table and figure caption
that a page holds between two markers is written and checked here.

A block is what lies between `<!-- NAME: begin -->` and `<!-- NAME: end -->` (the style of every
new block); older pages keep their own marker pair, given as `begin` and `end`.
"""

import os
import sys
from typing import Dict


def markers(name: str):
    """The marker pair of block NAME."""
    return f"<!-- {name}: begin -->", f"<!-- {name}: end -->"


def rewrite_between(doc: str, begin: str, end: str, block: str, check: bool, prog: str) -> int:
    """Replaces a page's text from `begin` to `end` (markers included) by `block`, which holds
    them; with `check` it only says whether the page is stale (exit 1). Exit 2, naming the page
    and the markers, when the page has no such block."""
    text = open(doc, encoding="utf-8").read()
    if begin not in text or end not in text:
        print(f"{prog}: {doc} has no {begin} ... {end} block", file=sys.stderr)
        return 2
    new = text[: text.index(begin)] + block + text[text.index(end) + len(end) :]
    if check:
        return 0 if new == text else 1
    with open(doc, "w", encoding="utf-8") as f:
        f.write(new)
    return 0


def rewrite(doc: str, blocks: Dict[str, str], check: bool, prog: str = "docblocks") -> int:
    """Writes each block NAME of `blocks` (its body, without markers) into `doc`; the largest exit
    of rewrite_between over them."""
    rc = 0
    for name, body in blocks.items():
        begin, end = markers(name)
        rc = max(rc, rewrite_between(doc, begin, end, f"{begin}\n{body.rstrip(chr(10))}\n{end}", check, prog))
    return rc


def block_text(page: str, name: str) -> str:
    """The body of block NAME of `page` (ValueError naming both when there is none)."""
    from asg_agent.paths import REPO

    begin, end = markers(name)
    text = open(page, encoding="utf-8").read()
    if begin + "\n" not in text or end not in text:
        raise ValueError(f"{os.path.relpath(page, REPO)}: no block {name!r}")
    return text.split(begin + "\n", 1)[1].split(end, 1)[0]
