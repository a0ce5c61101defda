"""docs/agent.md's table of campaign defaults, generated from the one table (asg_agent.defaults).

python3 -m asg_analysis defaults [--check]
"""

import argparse
import os
import sys

from asg_agent.defaults import doc_table
from asg_agent.paths import REPO
from asg_analysis.docblocks import rewrite

PROG = "python3 -m asg_analysis defaults"
PAGE = os.path.join(REPO, "docs", "agent.md")


def run(argv=None) -> int:
    p = argparse.ArgumentParser(prog=PROG, description=__doc__.split("\n\n")[0])
    p.add_argument("--check", action="store_true", help="exit 1 if the table is stale; write nothing")
    a = p.parse_args(argv)
    rc = rewrite(PAGE, {"defaults": doc_table()}, a.check, "defaults")
    if rc == 1:
        print(f"defaults: docs/agent.md's table is stale: {PROG}", file=sys.stderr)
    return rc
