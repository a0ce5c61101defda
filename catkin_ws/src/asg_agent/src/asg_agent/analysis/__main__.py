"""python3 -m asg_agent.analysis: the export tool (asg_agent.analysis.export)."""

import sys

from asg_agent.analysis.export import main

sys.exit(main())
