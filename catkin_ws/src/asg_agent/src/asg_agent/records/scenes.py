"""The scene of a stored or exported row: its request rebuilt from the experiment and the row's
positions, and what the camera saw ahead of a trajectory point (no ROS)."""

import os

import numpy as np

from asg_agent.paths import REPO


#: experiments read by scenario_of, by (path, modification time): a campaign's rows share one
#: (reading the YAML for each row took most of `protocol status`'s time)
_EXPERIMENTS = {}


def _experiment(name: str):
    from asg_agent.records.experiment import load_experiment

    path = os.path.join(REPO, "experiments", name + ".yaml")
    key = (path, os.stat(path).st_mtime_ns)
    if key not in _EXPERIMENTS:
        _EXPERIMENTS[key] = load_experiment(path)
    return _EXPERIMENTS[key]


def scenario_of(campaign: dict, row: dict) -> dict:
    """The request of an exported row: the experiment's fixed attributes with its positions (and
    its textural attributes, where the export has them)."""
    from asg_scenario.layout import with_positions

    exp = _experiment(campaign["experiment"])
    s = with_positions(exp.scenario, row["positions"])  # a deep copy: the cached experiment stays
    s["textural"].update(row.get("textural") or {})
    return s


def shadow_ahead(req: dict, xy: np.ndarray, i: int, reach: float = 20.0, half_width: float = 5.0) -> bool:
    """Whether an obstacle's cast shadow lies in the corridor `reach` m ahead of trajectory point i
    (heading from the point 1 s later), `half_width` m to either side: ground the camera sees."""
    from asg_scenario.votes import shadow_mask

    j = min(len(xy) - 1, i + 10)
    h = xy[j] - xy[i] if j > i else xy[i] - xy[max(0, i - 10)]
    if np.linalg.norm(h) < 1e-6:
        return False
    h = h / np.linalg.norm(h)
    n = np.array([-h[1], h[0]])
    a = np.arange(1.0, reach + 0.5, 1.0)[:, None, None]
    b = np.arange(-half_width, half_width + 0.5, 1.0)[None, :, None]
    p = xy[i] + a * h + b * n  # the grid of points, each as (xy[i] + a h) + b n
    return bool(shadow_mask(req, p[..., 0], p[..., 1]).any())
