"""python3 -m asg_analysis: figures over a campaign store (asg_analysis.figures), `coverage`, a
failure atlas's endpoint (asg_analysis.coverage), and `defaults [--check]`, docs/agent.md's table
of campaign defaults (asg_agent.defaults)."""

import os
import sys

if sys.argv[1:2] == ["defaults"]:
    from asg_agent.defaults import doc_table
    from asg_agent.paths import REPO
    from asg_analysis.docblocks import rewrite

    rc = rewrite(os.path.join(REPO, "docs", "agent.md"), {"defaults": doc_table()}, "--check" in sys.argv, "defaults")
    if rc == 1:
        print("defaults: docs/agent.md's table is stale: python3 -m asg_analysis defaults", file=sys.stderr)
    sys.exit(rc)

if sys.argv[1:2] == ["coverage"]:
    from asg_analysis.coverage import main

    sys.exit(main(sys.argv[2:]))

from asg_analysis.figures import main  # noqa: E402

sys.exit(main())
