"""python3 -m asg_analysis COMMAND [ARGS]: the one entry point (asg_analysis.commands)."""

import sys

from asg_analysis.commands import main

sys.exit(main())
