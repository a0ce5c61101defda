"""The campaign command on the in-process stand-in (tests; no ROS, no simulator):

    python3 -m stand_in.campaign EXPERIMENT.yaml --fake-workers N [campaign's options]

(with stand_in.environ(): catkin_ws/src/asg_agent/test first on PYTHONPATH). Every option of
`rosrun asg_agent campaign` (asg_agent.cli.campaign), plus --fake-workers: N stand-in workers
under test, and one stand-in pool of each reference role (which wiggles less). The command is
the production one, given these workers instead of ROS's (asg_agent.ros.campaign_pools.RosWorkers).
"""

import sys
import time

from asg_agent.cli import campaign
from stand_in.fake_pool import FakePool


class StandInWorkers:
    """The campaign's workers (asg_agent.cli.campaign.main's `workers`): pools of FakePool workers,
    nothing checked against a running stack, no stage times of nodes."""

    #: what the store records beside the campaign's settings: a campaign on the stand-in
    settings = {"fake": True}

    def options(self, p):
        p.add_argument("--fake-workers", type=int, required=True, help="N in-process stand-in workers (no ROS)")

    def names(self, a):
        if a.fake_workers < 1:
            raise ValueError("--fake-workers must be >= 1")
        return [f"fake_{i}" for i in range(a.fake_workers)]

    def numbered(self, role, first, n):
        return [f"fake_{role}_{i}" for i in range(n)]

    def pools(self, a, exp, workers, roles):
        """(pool under test, {role: reference pool}) of stand-in workers."""
        seed = int(time.time())
        pool = FakePool(len(workers), seed=seed)
        references = {
            role: FakePool(len(ws), seed=seed + 1 + k, gain=0.3, prefix=f"fake_{role}")
            for k, (role, ws) in enumerate(roles.items())
        }
        return pool, references

    def check(self, exp, settings, workers, roles):
        pass

    def collector(self, a, exp, settings, workers, roles):
        return None


def parse(argv):
    return campaign.parse(argv, StandInWorkers().options)


def main(argv=None) -> int:
    return campaign.main(argv, workers=StandInWorkers())


if __name__ == "__main__":
    sys.exit(main())
