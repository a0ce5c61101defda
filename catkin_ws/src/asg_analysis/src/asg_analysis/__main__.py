"""python3 -m asg_analysis: figures over a campaign store (asg_analysis.figures)."""

import sys

from asg_analysis.figures import main

sys.exit(main())
