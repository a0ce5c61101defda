"""Stand-ins shared by the campaign tests: a small campaign on the in-process pool, and a pool
that dies mid-episode as a killed process would (not a test module)."""

import os

from stand_in.fake_pool import FakePool
from asg_agent.campaign.loop import Campaign
from asg_agent.campaign.config import CampaignConfig
from asg_agent.records.experiment import load_experiment
from asg_agent.records.store import Store
from asg_agent.search.methods import make_method
from asg_agent.search.td3 import TD3Config

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", "..", ".."))
EXP = os.path.join(REPO, "experiments", "exp1.yaml")
SMALL = dict(hidden=32, batch_size=16, start_steps=20)


def campaign(tmp_path, name, pool, total=40, method="td3-per-asp", seed=7, store=None):
    exp = load_experiment(EXP)
    store = store or Store(str(tmp_path / "store.sqlite"))
    m = make_method(method, exp, seed, budget=total, td3_config=TD3Config(**SMALL))
    return Campaign(
        CampaignConfig(
            name=name,
            experiment=exp,
            method=m,
            store=store,
            pool=pool,
            total=total,
            seed=seed,
            checkpoint=str(tmp_path / f"{name}.ckpt"),
            slots=4,
            checkpoint_every=1,
        )
    )


def refused(exp, store, reward, references, name="g"):
    """The ValueError a 4-scenario campaign with this reward and these reference roles raises
    when it is built (None when it is not refused)."""
    try:
        Campaign(
            CampaignConfig(
                name=name,
                experiment=exp,
                method=make_method("random", exp, 1),
                store=store,
                pool=FakePool(1),
                total=4,
                seed=1,
                checkpoint="/x",
                reward=reward,
                references={role: FakePool(1) for role in references},
            )
        )
    except ValueError as e:
        return e
    return None


class Interrupt(Exception):
    pass


class DyingPool(FakePool):
    """Raises after `die_after` outcomes, as a killed process would stop mid-episode."""

    def __init__(self, die_after, **kw):
        super().__init__(**kw)
        self.die_after, self.seen = die_after, 0

    def poll(self, timeout):
        out = super().poll(timeout)
        self.seen += len(out)
        if self.seen > self.die_after:
            raise Interrupt()
        return out
