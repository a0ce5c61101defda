"""python3 -m asg_analysis: figures over a campaign store (asg_analysis.figures), and `coverage`,
a failure atlas's endpoint (asg_analysis.coverage)."""

import sys

if sys.argv[1:2] == ["coverage"]:
    from asg_analysis.coverage import main

    sys.exit(main(sys.argv[2:]))

from asg_analysis.figures import main  # noqa: E402

sys.exit(main())
