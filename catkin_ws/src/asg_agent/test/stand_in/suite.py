"""The suite command on the in-process stand-in (tests; no ROS, no simulator):

    python3 -m stand_in.suite run SUITE --fake-workers N [suite run's options]

(with stand_in.environ()). The production command (asg_agent.cli.suite), given these workers
instead of ROS's."""

import sys

from asg_agent.cli import suite
from stand_in.fake_pool import FakePool


class StandInWorkers:
    """The suite's workers (asg_agent.cli.suite.main's `workers`): N FakePool workers, whose
    segmenter runs no numerics."""

    def options(self, r):
        r.add_argument("--fake-workers", type=int, required=True, help="N in-process stand-in workers (no ROS)")

    def pool(self, a):
        return FakePool(a.fake_workers)

    def numerics(self, a) -> str:
        return ""


def main(argv=None) -> int:
    return suite.main(argv, workers=StandInWorkers())


if __name__ == "__main__":
    sys.exit(main())
