"""The suite command on the in-process stand-in (tests; no ROS, no simulator):

python3 -m asg_agent.testing.suite run SUITE --fake-workers N [suite run's options]
"""

import sys

from asg_agent.cli import suite
from asg_agent.testing.fake_pool import FakePool


def main(argv=None) -> int:
    return suite.main(argv, stand_in=FakePool)


if __name__ == "__main__":
    sys.exit(main())
