"""The campaign command on the in-process stand-in (tests; no ROS, no simulator):

    python3 -m asg_agent.testing.campaign EXPERIMENT.yaml --fake-workers N [campaign's options]

Every option of `rosrun asg_agent campaign` (asg_agent.cli.campaign), plus --fake-workers: N
stand-in workers under test, and one stand-in pool of each reference role (which wiggles less).
"""

import sys
import time

from asg_agent.cli import campaign
from asg_agent.testing.fake_pool import FakePool


def stand_in_pools(a, roles):
    """(pool under test, {role: reference pool}) of stand-in workers for parsed arguments `a`."""
    seed = int(time.time())
    pool = FakePool(a.fake_workers, seed=seed)
    references = {
        role: FakePool(len(ws), seed=seed + 1 + k, gain=0.3, prefix=f"fake_{role}")
        for k, (role, ws) in enumerate(roles.items())
    }
    return pool, references


def parse(argv):
    return campaign.parse(argv, stand_in=True)


def main(argv=None) -> int:
    return campaign.main(argv, stand_in=stand_in_pools)


if __name__ == "__main__":
    sys.exit(main())
