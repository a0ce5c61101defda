"""Experiment files: the fixed attributes of a search and its variable ones (no ROS imports).

An experiment file (YAML, `experiments/expN.yaml`) names a scenario file holding every fixed
attribute (landscape, sun, start, goal, speed, meshes and their counts, timeouts) and how the
search varies it. The action is the x, y of every obstacle instance, each scaled from [-1, 1] to
[0, landscape size], then one value per free textural attribute (weather, light), each scaled
from [-1, 1] to its range. Keys (docs/agent.md):

    name: exp1
    scenario: ../scenarios/exp1.yaml   # relative to this file
    perception: unet                   # unet or ground_truth (the stack the workers must run)
    model: flawed                      # unet only: shipped model name or path
    unet_backend: bf16                 # unet only: inference backend (asg_perception.inference)
    planner_config: planner.yaml       # a file of asg_planner/config, or a path
    episode_steps: 5
    sim_timeout: 60.0                  # [s] overrides the scenario's
    textural_free:                     # optional: textural attributes the search sets, [lo, hi]
      fog_visibility_m: [25.0, 500.0]  #   in the field's unit (docs/scenario-format.md)
      cloud_cover: [0.0, 1.0]
"""

import math
import os
from dataclasses import dataclass, field

import numpy as np
import yaml

from asg_scenario import ScenarioError, load_scenario
from asg_scenario.schema import TEXTURAL_FIELDS, strict_yaml_load
from asg_scenario.layout import instance_count, with_positions


class ExperimentError(ValueError):
    pass


KEYS = {
    "name",
    "scenario",
    "perception",
    "model",
    "unet_backend",
    "planner_config",
    "episode_steps",
    "sim_timeout",
    "description",
    "textural_free",
}
#: textural attributes a search may set (a number with a range; not the ground texture's seed)
FREE_TEXTURAL = {f.key: f for f in TEXTURAL_FIELDS if f.kind is float}
#: asg_perception.inference.BACKENDS (a test keeps the two equal; asg_agent does not import torch models)
UNET_BACKENDS = ("eager", "channels_last", "frozen", "bf16")
#: asg_perception.inference.DEFAULT_BACKEND: what a file without `unet_backend` means
DEFAULT_UNET_BACKEND = "bf16"
#: what a campaign whose settings lack `unet_backend` ran (every one before the key existed)
LEGACY_UNET_BACKEND = "channels_last"


@dataclass
class Experiment:
    name: str
    scenario: dict  #: the fixed attributes, validated
    perception: str = "unet"
    model: str = "flawed"
    planner_config: str = "planner.yaml"
    episode_steps: int = 5
    unet_backend: str = DEFAULT_UNET_BACKEND  #: part of the stack's identity: labels differ by backend
    source: str = ""
    text: str = field(default="", repr=False)  #: the file as read (stored with the campaign)
    #: (textural key, lo, hi) the search sets, in this order after the positions in the action
    textural_free: list = field(default_factory=list)

    @property
    def size(self) -> float:
        return float(self.scenario["structural"]["landscape"]["size"])

    @property
    def position_dim(self) -> int:
        return 2 * instance_count(self.scenario)

    @property
    def action_dim(self) -> int:
        return self.position_dim + len(self.textural_free)

    def to_positions(self, action) -> np.ndarray:
        """The action's first 2n values, [-1, 1] -> (n, 2) positions [m], rounded to 1 mm."""
        a = np.asarray(action, dtype=np.float64).reshape(-1)[: self.position_dim]
        a = np.clip(a.reshape(-1, 2), -1.0, 1.0)
        return np.round((a + 1.0) * 0.5 * self.size, 3)

    def to_textural(self, action) -> dict:
        """The action's values after the positions, [-1, 1] -> each free attribute's [lo, hi]
        (in its unit), rounded to 1e-3."""
        a = np.clip(np.asarray(action, dtype=np.float64).reshape(-1)[self.position_dim :], -1.0, 1.0)
        return {k: round(float(lo + (v + 1.0) * 0.5 * (hi - lo)), 3) for (k, lo, hi), v in zip(self.textural_free, a)}

    def to_action(self, xy) -> np.ndarray:
        return (np.asarray(xy, dtype=np.float64).reshape(-1) / self.size * 2.0 - 1.0).astype(np.float32)

    def request(self, action, scenario_id: int) -> dict:
        s = with_positions(self.scenario, self.to_positions(action))
        s["textural"].update(self.to_textural(action))
        s["scenario_id"] = int(scenario_id)
        s["name"] = f"{self.name}-{scenario_id}"
        return s


def load_experiment(path: str) -> Experiment:
    try:
        with open(path, encoding="utf-8") as f:
            text = f.read()
    except OSError as e:
        raise ExperimentError(f"{path}: cannot read ({e.strerror})") from None
    except UnicodeDecodeError as e:
        raise ExperimentError(f"{path}: not UTF-8 text (byte 0x{e.object[e.start]:02x} at offset {e.start})") from None
    try:
        data = strict_yaml_load(text)
    except yaml.YAMLError as e:
        raise ExperimentError(f"{path}: not valid YAML ({e})") from None
    except RecursionError:
        raise ExperimentError(f"{path}: nested too deeply to be an experiment file") from None
    if not isinstance(data, dict):
        raise ExperimentError(f"{path}: must be a mapping")
    problems = [f"{k}: unknown key (allowed: {', '.join(sorted(KEYS))})" for k in data if k not in KEYS]
    for key in ("name", "scenario"):
        if not isinstance(data.get(key), str) or not data.get(key):
            problems.append(f"{key}: required, a non-empty string")
    if data.get("perception", "unet") not in ("unet", "ground_truth"):
        problems.append(f"perception: {data.get('perception')!r}, must be unet or ground_truth")
    if data.get("unet_backend", DEFAULT_UNET_BACKEND) not in UNET_BACKENDS:
        problems.append(f"unet_backend: {data.get('unet_backend')!r}, must be one of {', '.join(UNET_BACKENDS)}")
    steps = data.get("episode_steps", 5)
    if isinstance(steps, bool) or not isinstance(steps, int) or not 1 <= steps <= 100:
        problems.append(f"episode_steps: {steps!r}, must be an integer in [1, 100]")
    timeout = data.get("sim_timeout")
    if timeout is not None and (
        isinstance(timeout, bool)
        or not isinstance(timeout, (int, float))
        or not math.isfinite(timeout)
        or not 0.1 <= timeout <= 3600
    ):
        problems.append(f"sim_timeout: {timeout!r}, must be a number in [0.1, 3600] s")
    for key in ("model", "planner_config", "description"):
        if key in data and not isinstance(data[key], str):
            problems.append(f"{key}: must be a string")
    free = []
    tf = data.get("textural_free", {})
    if not isinstance(tf, dict):
        problems.append("textural_free: must be a mapping of textural attribute to [lo, hi]")
        tf = {}
    for k, r in tf.items():
        f = FREE_TEXTURAL.get(k)
        if f is None:
            problems.append(
                f"textural_free.{k}: not a textural attribute a search can set (one of {', '.join(FREE_TEXTURAL)})"
            )
        elif (
            not isinstance(r, list)
            or len(r) != 2
            or any(isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) for v in r)
        ):
            problems.append(f"textural_free.{k}: {r!r}, must be [lo, hi], two numbers in {f.unit}")
        elif not f.lo <= r[0] < r[1] <= f.hi:
            problems.append(
                f"textural_free.{k}: [{r[0]}, {r[1]}] must satisfy {f.lo:g} <= lo < hi <= {f.hi:g} ({f.unit})"
            )
        else:
            free.append((k, float(r[0]), float(r[1])))
    if problems:
        raise ExperimentError(f"{path}: " + "; ".join(problems))
    spath = data["scenario"]
    if not os.path.isabs(spath):
        spath = os.path.join(os.path.dirname(os.path.abspath(path)), spath)
    try:
        scenario = load_scenario(spath)
    except ScenarioError as e:
        raise ExperimentError(f"{path}: scenario {spath}: {e}") from None
    if timeout is not None:
        scenario["operational"]["sim_timeout"] = float(timeout)
    if instance_count(scenario) == 0:
        raise ExperimentError(f"{path}: the scenario has no obstacle to place")
    return Experiment(
        name=data["name"],
        scenario=scenario,
        perception=data.get("perception", "unet"),
        model=data.get("model", "flawed"),
        planner_config=data.get("planner_config", "planner.yaml"),
        episode_steps=steps,
        source=os.path.abspath(path),
        text=text,
        unet_backend=data.get("unet_backend", DEFAULT_UNET_BACKEND),
        textural_free=free,
    )
