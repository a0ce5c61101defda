"""TD3 with prioritized experience replay and the action saturation penalty (no ROS imports).

One plain class for any continuous-control problem with actions in [-1, 1]^n: `act`, `observe`,
`update`, `save`, `load`. TD3 (Fujimoto et al. 2018): twin critics (the smaller target value),
target policy smoothing (clipped Gaussian noise on the target action), delayed actor and target
updates. PER (per_buffer.py) weights the critic loss by importance weights and re-prioritises by
the TD error.

Action saturation penalty (ASP, this project's design; the paper names it without a formula).
The actor's last layer gives pre-squash outputs u, and a = tanh(u). Once |u| grows past ~2 the
action sits at the edge of its range and tanh's gradient (1 - a^2 < 0.07) all but stops the
critic's gradient from moving it back: early in training, when the critic is still poor, an
actor that drifts to the edges stays there, and the generator only ever places obstacles on
the landscape's border. The penalty is a hinge on the pre-squash outputs,

    L_ASP = lambda(k) * mean( max(0, |u| - u0)^2 ),   lambda(k) = lambda0 * exp(-k / tau),

added to the actor loss: zero while |u| <= u0 (tanh(u0) = 0.96 for u0 = 2, so interior actions
are not biased), quadratic beyond, and fading with the update count k so that a well-trained
critic may still ask for edge positions later. docs/agent.md gives its measured effect.
"""

import io
import os
import tempfile
from dataclasses import asdict, dataclass, fields
from typing import Dict, Optional

import numpy as np
import torch
import torch.nn as nn
import torch.nn.functional as F

from asg_agent.search.per_buffer import PrioritizedReplay


@dataclass
class TD3Config:
    """Every hyperparameter of the agent (defaults: docs/agent.md)."""

    hidden: int = 256  #: units in each of the two hidden layers of actor and critics
    actor_lr: float = 3e-4  #: Adam learning rate of the actor
    critic_lr: float = 3e-4  #: Adam learning rate of the critics
    gamma: float = 0.9  #: discount per step (episodes are 5 steps)
    tau: float = 0.005  #: Polyak factor of the target networks
    policy_noise: float = 0.2  #: std of the target policy smoothing noise
    noise_clip: float = 0.5  #: its clip
    policy_delay: int = 2  #: critic updates per actor (and target) update
    exploration_noise: float = 0.2  #: std of the Gaussian noise added to acted actions
    batch_size: int = 128  #: transitions per update
    buffer_size: int = 100000  #: replay capacity
    start_steps: int = 100  #: transitions acted uniformly at random before the actor is used
    updates_per_step: int = 2  #: gradient updates per observed transition (once warm)
    per: bool = True  #: prioritized replay (False: uniform replay, weights 1)
    per_alpha: float = 0.6  #: priority exponent
    per_beta0: float = 0.4  #: initial importance-weight exponent, annealed to 1
    per_beta_steps: int = 0  #: batches over which beta reaches 1; 0: the campaign's, set by TD3Search
    per_eps: float = 1e-3  #: added to |TD error|
    asp: bool = True  #: action saturation penalty
    asp_lambda0: float = 1.0  #: its initial weight
    asp_u0: float = 2.0  #: pre-squash magnitude where it starts
    asp_tau: float = 3000.0  #: updates over which its weight falls by e
    normalize_q: bool = True  #: divide the actor's -Q by its batch mean |Q| (scale-free); TD3Search: on with ASP only
    #: weight of mean((actor(s) - a)^2) over replayed (s, a): keeps the actor near its data; 1, the
    #: setting of every documented campaign (0: off, the variant that collapses to the border). The
    #: one home of this default: `campaign --bc-weight` takes it from here.
    bc_weight: float = 1.0
    seed: int = 0  #: seeds torch and numpy generators of this agent


class Actor(nn.Module):
    def __init__(self, state_dim, action_dim, hidden):
        super().__init__()
        self.l1, self.l2, self.l3 = (
            nn.Linear(state_dim, hidden),
            nn.Linear(hidden, hidden),
            nn.Linear(hidden, action_dim),
        )

    def pre_squash(self, s):
        return self.l3(F.relu(self.l2(F.relu(self.l1(s)))))

    def forward(self, s):
        return torch.tanh(self.pre_squash(s))


class Critic(nn.Module):
    def __init__(self, state_dim, action_dim, hidden):
        super().__init__()
        self.q1 = nn.Sequential(
            nn.Linear(state_dim + action_dim, hidden),
            nn.ReLU(),
            nn.Linear(hidden, hidden),
            nn.ReLU(),
            nn.Linear(hidden, 1),
        )
        self.q2 = nn.Sequential(
            nn.Linear(state_dim + action_dim, hidden),
            nn.ReLU(),
            nn.Linear(hidden, hidden),
            nn.ReLU(),
            nn.Linear(hidden, 1),
        )

    def forward(self, s, a):
        x = torch.cat([s, a], 1)
        return self.q1(x), self.q2(x)


class TD3Agent:
    def __init__(self, state_dim: int, action_dim: int, config: Optional[TD3Config] = None):
        self.config = c = config or TD3Config()
        if c.per and c.per_beta_steps < 1:
            raise ValueError(
                "TD3Config.per_beta_steps must be >= 1 with PER: the batches over which beta "
                "reaches 1 (TD3Search sets it to the campaign's)"
            )
        self.state_dim, self.action_dim = state_dim, action_dim
        self.torch_gen = torch.Generator().manual_seed(c.seed)
        self.rng = np.random.default_rng(c.seed)
        with torch.random.fork_rng():
            torch.manual_seed(c.seed)
            self.actor = Actor(state_dim, action_dim, c.hidden)
            self.critic = Critic(state_dim, action_dim, c.hidden)
        self.actor_target = Actor(state_dim, action_dim, c.hidden)
        self.actor_target.load_state_dict(self.actor.state_dict())
        self.critic_target = Critic(state_dim, action_dim, c.hidden)
        self.critic_target.load_state_dict(self.critic.state_dict())
        self.actor_opt = torch.optim.Adam(self.actor.parameters(), lr=c.actor_lr)
        self.critic_opt = torch.optim.Adam(self.critic.parameters(), lr=c.critic_lr)
        self.buffer = PrioritizedReplay(
            c.buffer_size,
            state_dim,
            action_dim,
            c.per_alpha if c.per else 0.0,
            c.per_beta0,
            max(1, c.per_beta_steps),
            c.per_eps,
        )
        self.observed = 0  # transitions observed
        self.acted = 0  # actions chosen
        self.updates = 0  # critic updates done

    # -- acting ---------------------------------------------------------------------------------
    def act(self, state, explore: bool = True) -> np.ndarray:
        """An action in [-1, 1]^n: uniform during warm-up, else the actor plus Gaussian noise."""
        self.acted += 1
        if explore and self.observed < self.config.start_steps:
            return self.rng.uniform(-1.0, 1.0, self.action_dim).astype(np.float32)
        with torch.no_grad():
            a = self.actor(torch.as_tensor(np.asarray(state, np.float32))[None])[0].numpy()
        if explore:
            a = a + self.rng.normal(0.0, self.config.exploration_noise, self.action_dim)
        return np.clip(a, -1.0, 1.0).astype(np.float32)

    def pre_squash(self, states) -> np.ndarray:
        with torch.no_grad():
            return self.actor.pre_squash(torch.as_tensor(np.asarray(states, np.float32))).numpy()

    # -- learning -------------------------------------------------------------------------------
    def observe(self, s, a, r: float, s2, done: bool):
        self.buffer.add(s, a, r, s2, done)
        self.observed += 1

    def asp_weight(self) -> float:
        c = self.config
        return c.asp_lambda0 * float(np.exp(-self.updates / c.asp_tau)) if c.asp else 0.0

    def update(self) -> Optional[Dict[str, float]]:
        """`updates_per_step` gradient steps; None while the buffer holds less than a batch."""
        c = self.config
        if len(self.buffer) < min(c.batch_size, c.start_steps) or self.observed < c.start_steps:
            return None
        out = {}
        for _ in range(c.updates_per_step):
            out = self._update_once()
        return out

    def _update_once(self) -> Dict[str, float]:
        c = self.config
        b = self.buffer.sample(c.batch_size, self.rng)
        s, a = torch.from_numpy(b["state"]), torch.from_numpy(b["action"])
        r, s2, nd = torch.from_numpy(b["reward"]), torch.from_numpy(b["next_state"]), torch.from_numpy(b["not_done"])
        w = torch.from_numpy(b["weight"]) if c.per else torch.ones_like(r)
        with torch.no_grad():
            noise = (torch.randn(a.shape, generator=self.torch_gen) * c.policy_noise).clamp(-c.noise_clip, c.noise_clip)
            a2 = (self.actor_target(s2) + noise).clamp(-1.0, 1.0)
            q1t, q2t = self.critic_target(s2, a2)
            y = r + nd * c.gamma * torch.min(q1t, q2t)
        q1, q2 = self.critic(s, a)
        td1, td2 = q1 - y, q2 - y
        critic_loss = (w * (td1.pow(2) + td2.pow(2))).mean()
        self.critic_opt.zero_grad()
        critic_loss.backward()
        self.critic_opt.step()
        self.buffer.update_priorities(b["index"], (0.5 * (td1.abs() + td2.abs())).detach().numpy())
        self.updates += 1
        out = {
            "critic_loss": float(critic_loss),
            "q": float(q1.mean()),
            "per_beta": self.buffer.beta() if c.per else None,
        }
        if self.updates % c.policy_delay == 0:
            u = self.actor.pre_squash(s)
            q = self.critic(s, torch.tanh(u))[0]
            # Scale-free policy objective: -Q divided by the batch's mean |Q| (not differentiated),
            # so the penalty's weight means the same whatever the reward scale (the proxy is
            # 1 to 8, Q ten times that): without it the critic's gradient swamped the penalty and
            # the first Exp. 1 campaign's actor went to the landscape's edges (docs/agent.md).
            actor_loss, bc = self.actor_terms(u, q, a, w)
            asp = (F.relu(u.abs() - c.asp_u0).pow(2)).mean()
            loss = actor_loss + self.asp_weight() * asp
            if c.bc_weight > 0:  # behaviour regularisation (TD3+BC's term): no leap off the data
                loss = loss + c.bc_weight * bc
            self.actor_opt.zero_grad()
            loss.backward()
            self.actor_opt.step()
            with torch.no_grad():
                for net, tgt in ((self.actor, self.actor_target), (self.critic, self.critic_target)):
                    for p, tp in zip(net.parameters(), tgt.parameters()):
                        tp.mul_(1 - c.tau).add_(c.tau * p)
            # Saturation: the share of the batch's actions within 1 % of the border (|a| >= 0.99).
            sat = float((torch.tanh(u.detach()).abs() >= 0.99).float().mean())
            out.update(actor_loss=float(actor_loss), asp=float(asp), asp_weight=self.asp_weight(), actor_saturation=sat)
        return out

    def actor_terms(self, u, q, a, w):
        """The actor's objective and its behaviour term over a replayed batch: pre-squash actions
        u, Q of the squashed actions q, replayed actions a, importance weights w (ones without
        PER). Both are expectations under the replay distribution, so with PER both carry the
        importance weights, as the critic's loss does (issue #25)."""
        scale = q.abs().mean().detach() + 1e-6 if self.config.normalize_q else 1.0
        actor_loss = -(w * q).mean() / scale
        bc = (w * (torch.tanh(u) - a).pow(2)).mean()
        return actor_loss, bc

    # -- persistence ----------------------------------------------------------------------------
    def state_dict(self) -> dict:
        return {
            "config": asdict(self.config),
            "dims": (self.state_dim, self.action_dim),
            "actor": self.actor.state_dict(),
            "critic": self.critic.state_dict(),
            "actor_target": self.actor_target.state_dict(),
            "critic_target": self.critic_target.state_dict(),
            "actor_opt": self.actor_opt.state_dict(),
            "critic_opt": self.critic_opt.state_dict(),
            "buffer": self.buffer.state_dict(),
            "rng": self.rng.bit_generator.state,
            "torch_gen": self.torch_gen.get_state(),
            "counters": (self.observed, self.acted, self.updates),
        }

    def load_state_dict(self, d: dict):
        if tuple(d["dims"]) != (self.state_dim, self.action_dim):
            raise ValueError(
                f"checkpoint is for state/action sizes {tuple(d['dims'])}, "
                f"this agent has {(self.state_dim, self.action_dim)}"
            )
        for key in ("actor", "critic", "actor_target", "critic_target", "actor_opt", "critic_opt"):
            getattr(self, key).load_state_dict(d[key])
        self.buffer.load_state_dict(d["buffer"])
        self.rng.bit_generator.state = d["rng"]
        self.torch_gen.set_state(d["torch_gen"])
        self.observed, self.acted, self.updates = d["counters"]

    def save(self, path: str):
        """Atomically (a temporary file, then rename): a kill leaves the previous file usable."""
        save_atomic(self.state_dict(), path)

    @classmethod
    def load(cls, path: str) -> "TD3Agent":
        d = load_checked(path)
        known = {f.name for f in fields(TD3Config)}
        cfg = {k: v for k, v in d["config"].items() if k in known}
        cfg.setdefault("normalize_q", False)  # checkpoints from before the option trained without it
        agent = cls(*d["dims"], TD3Config(**cfg))
        agent.load_state_dict(d)
        return agent


def save_atomic(obj, path: str):
    folder = os.path.dirname(os.path.abspath(path))
    os.makedirs(folder, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=".tmp-", dir=folder)
    try:
        with os.fdopen(fd, "wb") as f:
            torch.save(obj, f)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def load_checked(path: str):
    """torch.load with a clear error for a missing, truncated or foreign file."""
    if not os.path.isfile(path):
        raise FileNotFoundError(f"{path}: no such checkpoint")
    try:
        with open(path, "rb") as f:
            return torch.load(io.BytesIO(f.read()), map_location="cpu")
    except Exception as e:  # torch raises several kinds for a damaged file
        raise ValueError(f"{path}: not a readable checkpoint ({type(e).__name__}: {e})") from None
