"""Experiment files: the fixed attributes of a search and its variable ones (no ROS imports).

An experiment file (YAML, `experiments/expN.yaml`) names a scenario file holding every fixed
attribute (landscape, sun, start, goal, speed, meshes and their counts, timeouts) and how the
search varies it. The action is the x, y of every obstacle instance, each scaled from [-1, 1] to
[0, landscape size], then one value per free textural attribute (weather, light), each scaled
from [-1, 1] to its range. Keys (docs/agent.md):

    name: exp1
    scenario: ../scenarios/exp1.yaml   # relative to this file
    stack: paper                       # the stack under test: paper (segmenter + voting planner)
                                       # or depth (asg_depth_stack, cmd_vel; docs/your-stack.md)
    perception: unet                   # paper only: unet or ground_truth (the workers must run it)
    model: flawed                      # unet only: shipped model name or path
    unet_backend: bf16                 # unet only: inference backend (asg_perception.inference)
    planner_config: planner.yaml       # a file of asg_planner/config, or a path
    episode_steps: 5
    sim_timeout: 60.0                  # [s] overrides the scenario's
    textural_free:                     # optional: textural attributes the search sets, [lo, hi]
      fog_visibility_m: [25.0, 500.0]  #   in the field's unit (docs/scenario-format.md)
      cloud_cover: [0.0, 1.0]
    terrain_free:                      # optional: the ground's shape the search sets (issue #27)
      amplitude_m: [0.0, 1.5]          #   [m] the rolling ground's, at most wavelength_m / 10
      hill_height_m: [-3.0, 3.0]       #   [m] one per hill of the scenario; |h| <= its radius_m / 2
      hill_positions: true             #   every hill's x, y over the landscape, as the obstacles'
    action_space: absolute             # how the action places an obstacle: absolute (the paper's:
                                       #   x, y over the landscape), route (along the straight
                                       #   start-goal route and a signed lateral offset; issue #54)
                                       #   or route-wide (the same, the offset reaching the
                                       #   landscape's edge; issue #67)
    route_lateral_m: 10.0              # route, route-wide: [m] the offset's dense part (below)

A file may build on others: `base: exp1.yaml` (or a list, applied in order), relative to its own
folder, and its keys override theirs (mappings merged key by key, anything else replaced;
`effective`). A campaign stores the effective experiment (`Experiment.text`).

With `action_space: route` each obstacle's two values are (u, v) in [-1, 1]: u sets the fraction
of the way from start to goal over the part outside the safety radii, v the lateral offset
v * route_lateral_m (asg_scenario.layout.RouteFrame). The scene space is the route band; what the
search may vary is otherwise the same (the obstacles' classes and counts stay the scenario's).

With `action_space: route-wide` (issue #67) u is the same and v maps piecewise linearly: |v| <= 1/2
covers the route band |d| <= route_lateral_m (at half the route space's resolution), and 1/2 < |v|
<= 1 covers the rest, out to the farthest corner of the landscape's square from the route line
(`RouteFrame.edge_m`; a point beyond the square is clipped onto its border: about 13 % of uniform
obstacles on Exp. 1). Not every layout of the square is reachable: along the route u covers only
the part outside the safety radii, so a point whose projection on the route falls behind the
start's safety radius or beyond the goal's is not (about 25 % of Exp. 1's square outside the
safety discs: the corners behind the start and beyond the goal). Every obstacle may still be near
the route or out of its way, and half of each obstacle's range lies in the band. Nothing in the
map depends on an obstacle's class.

The action then goes on with the terrain values, in this order: the amplitude, one height per
hill, one x, y per hill.
"""

import copy
import math
import os
from dataclasses import dataclass, field
from typing import Optional

import numpy as np
import yaml
from asg_perception.numerics import BACKENDS, DEFAULT_BACKEND
from asg_scenario import ScenarioError, load_scenario
from asg_scenario.schema import TEXTURAL_FIELDS, strict_yaml_load
from asg_scenario.layout import RouteFrame, instance_count, with_positions

from asg_agent.records import stacks


class ExperimentError(ValueError):
    pass


KEYS = {
    "name",
    "stack",
    "scenario",
    "perception",
    "model",
    "unet_backend",
    "planner_config",
    "episode_steps",
    "sim_timeout",
    "description",
    "textural_free",
    "terrain_free",
    "action_space",
    "route_lateral_m",
}
#: how an action places obstacles (docs/agent.md): over the landscape, or relative to the route
ACTION_SPACES = ("absolute", "route", "route-wide")
#: the action spaces relative to the route (route_lateral_m applies)
ROUTE_SPACES = ("route", "route-wide")
TERRAIN_FREE_KEYS = ("amplitude_m", "hill_height_m", "hill_positions")
#: textural attributes a search may set (a number with a range; not the ground texture's seed)
FREE_TEXTURAL = {f.key: f for f in TEXTURAL_FIELDS if f.kind is float}
#: the U-Net backends, and what a file without `unet_backend` means: asg_perception.numerics's
#: (their one home, a module without torch)
UNET_BACKENDS, DEFAULT_UNET_BACKEND = BACKENDS, DEFAULT_BACKEND
#: what a campaign whose settings lack `unet_backend` ran (every one before the key existed)
LEGACY_UNET_BACKEND = "channels_last"


@dataclass
class Experiment:
    name: str
    scenario: dict  #: the fixed attributes, validated
    stack: str = "paper"  #: the name of the stack under test (its registration's, campaign.stacks)
    perception: str = "unet"
    model: str = "flawed"
    planner_config: str = "planner.yaml"
    episode_steps: int = 5
    unet_backend: str = DEFAULT_UNET_BACKEND  #: part of the stack's identity: labels differ by backend
    source: str = ""
    stack_file: str = ""  #: the stack's registration launch file, absolute (records.stacks)
    sim_time: bool = False  #: the stack runs on simulated time (its registration's sim_time)
    #: the experiment as a campaign stores it: the file as read, or, for a file with a base, the
    #: effective mapping (`effective`) as YAML
    text: str = field(default="", repr=False)
    #: (textural key, lo, hi) the search sets, in this order after the positions in the action
    textural_free: list = field(default_factory=list)
    #: (lo, hi) [m] of the rolling ground's amplitude the search sets, or None
    amplitude_free: Optional[tuple] = None
    #: (lo, hi) [m] of every hill's height the search sets, or None
    hill_height_free: Optional[tuple] = None
    hill_positions_free: bool = False
    action_space: str = "absolute"  #: ACTION_SPACES
    route_lateral_m: float = 10.0  #: [m] route only: the largest lateral offset

    @property
    def hills(self) -> int:
        return len(self.scenario["structural"].get("terrain", {}).get("hills", []))

    @property
    def terrain_dim(self) -> int:
        return (
            (self.amplitude_free is not None)
            + (self.hills if self.hill_height_free is not None else 0)
            + (2 * self.hills if self.hill_positions_free else 0)
        )

    @property
    def size(self) -> float:
        return float(self.scenario["structural"]["landscape"]["size"])

    @property
    def position_dim(self) -> int:
        return 2 * instance_count(self.scenario)

    @property
    def action_dim(self) -> int:
        return self.position_dim + len(self.textural_free) + self.terrain_dim

    def to_positions(self, action) -> np.ndarray:
        """The action's first 2n values, [-1, 1] -> (n, 2) positions [m], rounded to 1 mm: over
        the landscape, or (action_space route) along and across the route."""
        a = np.asarray(action, dtype=np.float64).reshape(-1)[: self.position_dim]
        return self.positions_of(a[None])[0]

    def positions_of(self, actions) -> np.ndarray:
        """`to_positions` of m actions at once: (m, action_dim or more) -> (m, n, 2) [m]."""
        a = np.asarray(actions, dtype=np.float64)
        a = np.clip(a.reshape(a.shape[0], -1)[:, : self.position_dim].reshape(a.shape[0], -1, 2), -1.0, 1.0)
        if self.action_space in ROUTE_SPACES:
            route = RouteFrame(self.scenario)
            lo, hi = route.t_range
            t = lo + (a[..., 0] + 1.0) * 0.5 * (hi - lo)
            return np.round(route.point(t, self.lateral_m(a[..., 1], route)), 3)
        return np.round((a + 1.0) * 0.5 * self.size, 3)

    def lateral_m(self, v, route: Optional[RouteFrame] = None) -> np.ndarray:
        """[m] the signed lateral offset of action values v in [-1, 1] (route action spaces)."""
        v = np.clip(np.asarray(v, dtype=np.float64), -1.0, 1.0)
        if self.action_space != "route-wide":
            return v * self.route_lateral_m
        edge = max((route or RouteFrame(self.scenario)).edge_m, self.route_lateral_m)
        a = np.abs(v)
        d = np.where(
            a <= 0.5,
            2.0 * a * self.route_lateral_m,
            self.route_lateral_m + (2.0 * a - 1.0) * (edge - self.route_lateral_m),
        )
        return np.sign(v) * d

    def to_textural(self, action) -> dict:
        """The action's values after the positions, [-1, 1] -> each free attribute's [lo, hi]
        (in its unit), rounded to 1e-3."""
        a = np.clip(np.asarray(action, dtype=np.float64).reshape(-1)[self.position_dim :], -1.0, 1.0)
        return {k: round(float(lo + (v + 1.0) * 0.5 * (hi - lo)), 3) for (k, lo, hi), v in zip(self.textural_free, a)}

    def to_terrain(self, action) -> dict:
        """The scenario's structural.terrain with the action's terrain values (after the positions
        and the textural values) applied, each scaled from [-1, 1], rounded to 1 mm."""
        terrain = copy.deepcopy(self.scenario["structural"].get("terrain", {}))
        k = self.position_dim + len(self.textural_free)
        a = np.clip(np.asarray(action, dtype=np.float64).reshape(-1)[k : k + self.terrain_dim], -1.0, 1.0)

        def scale(v, lo, hi):
            return round(float(lo + (v + 1.0) * 0.5 * (hi - lo)), 3)

        i = 0
        if self.amplitude_free is not None:
            terrain["amplitude_m"] = scale(a[i], *self.amplitude_free)
            i += 1
        if self.hill_height_free is not None:
            for hill in terrain["hills"]:
                hill["height_m"] = scale(a[i], *self.hill_height_free)
                i += 1
        if self.hill_positions_free:
            for hill in terrain["hills"]:
                hill["x"], hill["y"] = scale(a[i], 0.0, self.size), scale(a[i + 1], 0.0, self.size)
                i += 2
        return terrain

    def to_action(self, xy) -> np.ndarray:
        """Positions [m] -> the action's first 2n values (absolute action space only)."""
        if self.action_space != "absolute":
            raise ValueError(f"{self.name}: to_action needs the absolute action space, not {self.action_space!r}")
        return (np.asarray(xy, dtype=np.float64).reshape(-1) / self.size * 2.0 - 1.0).astype(np.float32)

    def request(self, action, scenario_id: int) -> dict:
        s = with_positions(self.scenario, self.to_positions(action))
        s["textural"].update(self.to_textural(action))
        if self.terrain_dim:
            s["structural"]["terrain"] = self.to_terrain(action)
        s["scenario_id"] = int(scenario_id)
        s["name"] = f"{self.name}-{scenario_id}"
        return s


def _read(path: str):
    """(text, mapping) of an experiment file; ExperimentError naming what is wrong."""
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
    return text, data


#: the key naming the file(s) an experiment file builds on (docs/agent.md, "Problem framing")
BASE_KEY = "base"
#: the keys whose relative paths are read from the file's folder (a stack's only as a .launch file)
PATH_KEYS = ("scenario", "stack")


def _merge(under: dict, over: dict) -> dict:
    """`under` overridden by `over`: mappings merged key by key, any other value replaced."""
    out = dict(under)
    for k, v in over.items():
        out[k] = _merge(out[k], v) if isinstance(v, dict) and isinstance(out.get(k), dict) else v
    return out


def _rebased(data: dict, src: str, dst: str) -> dict:
    """A base's mapping with its relative paths (PATH_KEYS) read from folder `dst` instead of `src`."""
    out = dict(data)
    for k in PATH_KEYS:
        v = out.get(k)
        if src != dst and isinstance(v, str) and v and not os.path.isabs(v) and not v.startswith("~"):
            if k == "scenario" or v.endswith(".launch"):
                out[k] = os.path.relpath(os.path.join(src, v), dst)
    return out


def _compose(path: str, within: tuple = ()):
    """(text, effective mapping, the base files it was composed of) of an experiment file:
    each base's effective mapping in order, then the file's own keys (`_merge`). `within`: the
    files whose bases are being read (a cycle); ExperimentError naming the file."""
    here = os.path.abspath(path)
    text, data = _read(path)
    if BASE_KEY not in data:
        return text, data, []
    names = data.pop(BASE_KEY)
    names = [names] if isinstance(names, str) else names
    if not isinstance(names, list) or not names or not all(isinstance(n, str) and n.strip() for n in names):
        raise ExperimentError(f"{path}: base: {names!r}, must be a file name or a list of them (relative to this file)")
    merged, used, chain = {}, [], within + (here,)
    for name in names:
        base = os.path.normpath(os.path.join(os.path.dirname(here), name))
        if base in chain:
            cycle = " -> ".join(os.path.basename(f) for f in chain[chain.index(base) :] + (base,))
            raise ExperimentError(f"{path}: base {name}: a cycle of bases ({cycle})")
        if not os.path.isfile(base):
            raise ExperimentError(f"{path}: base {name}: no such file ({base})")
        _, bdata, bused = _compose(base, chain)
        merged = _merge(merged, _rebased(bdata, os.path.dirname(base), os.path.dirname(here)))
        used += bused + [base]
    return text, _merge(merged, data), used


def _composed(path: str):
    try:
        return _compose(path)
    except RecursionError:
        raise ExperimentError(f"{path}: nested too deeply to be an experiment file") from None


def effective(path: str) -> dict:
    """The effective mapping of an experiment file: its own keys over its bases' (`base`), not
    checked (load_experiment checks it). ExperimentError naming the file."""
    return _composed(path)[1]


class _Dumper(yaml.SafeDumper):
    """Block style, but a list of scalars on one line (`[25.0, 500.0]`), as the files write it."""

    def represent_flat_list(self, data):
        flat = not any(isinstance(v, (list, dict)) for v in data)
        return self.represent_sequence("tag:yaml.org,2002:seq", data, flow_style=flat)


_Dumper.add_representer(list, _Dumper.represent_flat_list)


def _effective_text(path: str, data: dict, used: list) -> str:
    """The effective mapping of a file with a base as YAML, headed by the files it came from."""
    here = os.path.dirname(os.path.abspath(path))
    head = ", ".join(os.path.relpath(f, here) for f in dict.fromkeys(used))
    body = yaml.dump(data, Dumper=_Dumper, sort_keys=False, default_flow_style=False, allow_unicode=True)
    return f"# {os.path.basename(path)} over its bases ({head}): the effective experiment\n" + body


def _textural_free(data: dict, problems: list) -> list:
    """[(key, lo, hi)] of the file's textural_free; each problem appended to `problems`."""
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
    return free


def _terrain_free(data: dict, problems: list):
    """({amplitude_m, hill_height_m: (lo, hi)}, hill_positions) of the file's terrain_free."""
    terrain_free = data.get("terrain_free", {})
    if not isinstance(terrain_free, dict):
        problems.append("terrain_free: must be a mapping (keys: " + ", ".join(TERRAIN_FREE_KEYS) + ")")
        terrain_free = {}
    for k in terrain_free:
        if k not in TERRAIN_FREE_KEYS:
            problems.append(f"terrain_free.{k}: unknown key (allowed: {', '.join(TERRAIN_FREE_KEYS)})")
    ranges = {}
    for k, (lo_lim, hi_lim) in (("amplitude_m", (0.0, 5.0)), ("hill_height_m", (-10.0, 10.0))):
        if k not in terrain_free:
            continue
        r = terrain_free[k]
        if (
            not isinstance(r, list)
            or len(r) != 2
            or any(isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) for v in r)
        ):
            problems.append(f"terrain_free.{k}: {r!r}, must be [lo, hi], two numbers in m")
        elif not lo_lim <= r[0] < r[1] <= hi_lim:
            problems.append(f"terrain_free.{k}: [{r[0]}, {r[1]}] must satisfy {lo_lim:g} <= lo < hi <= {hi_lim:g} (m)")
        else:
            ranges[k] = (float(r[0]), float(r[1]))
    hill_positions = terrain_free.get("hill_positions", False)
    if not isinstance(hill_positions, bool):
        problems.append(f"terrain_free.hill_positions: {hill_positions!r}, must be true or false")
        hill_positions = False
    return ranges, hill_positions


def _check_terrain(scenario: dict, ranges: dict, hill_positions: bool, problems: list):
    """Every request the search can make must be a valid scene: the ranges within the scenario's
    steepness bounds (docs/scenario-format.md)."""
    terrain = scenario["structural"]["terrain"]
    if "amplitude_m" in ranges and ranges["amplitude_m"][1] > terrain["wavelength_m"] / 10.0:
        problems.append(
            f"terrain_free.amplitude_m: hi {ranges['amplitude_m'][1]:g} m is too steep for the scenario's "
            f"wavelength_m {terrain['wavelength_m']:g} (at most wavelength_m / 10)"
        )
    if ("hill_height_m" in ranges or hill_positions) and not terrain["hills"]:
        problems.append(
            "terrain_free: hill_height_m and hill_positions need hills in the scenario's structural.terrain"
        )
    if "hill_height_m" in ranges and terrain["hills"]:
        lim = min(h["radius_m"] for h in terrain["hills"]) / 2.0
        if max(abs(v) for v in ranges["hill_height_m"]) > lim:
            problems.append(
                f"terrain_free.hill_height_m: {list(ranges['hill_height_m'])} is too steep for the smallest hill "
                f"(|height| at most radius_m / 2 = {lim:g} m)"
            )


def load_experiment(path: str) -> Experiment:
    text, data, used = _composed(path)
    text = _effective_text(path, data, used) if used else text
    problems = [f"{k}: unknown key (allowed: {', '.join(sorted(KEYS | {BASE_KEY}))})" for k in data if k not in KEYS]
    for key in ("name", "scenario"):
        if not isinstance(data.get(key), str) or not data.get(key):
            problems.append(f"{key}: required, a non-empty string")
    registration = None
    try:
        registration = stacks.load(data.get("stack", "paper"), os.path.dirname(os.path.abspath(path)))
    except stacks.RegistrationError as e:
        problems.append(str(e))
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
    free = _textural_free(data, problems)
    ranges, hill_positions = _terrain_free(data, problems)
    space = data.get("action_space", "absolute")
    if space not in ACTION_SPACES:
        problems.append(f"action_space: {space!r}, must be one of {', '.join(ACTION_SPACES)}")
    lateral = data.get("route_lateral_m", 10.0)
    if isinstance(lateral, bool) or not isinstance(lateral, (int, float)) or not 0.0 < lateral <= 1000.0:
        problems.append(f"route_lateral_m: {lateral!r}, must be a number in (0, 1000] m")
    elif "route_lateral_m" in data and space not in ROUTE_SPACES:
        problems.append(f"route_lateral_m: only with action_space {' or '.join(ROUTE_SPACES)}")
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
    _check_terrain(scenario, ranges, hill_positions, problems)
    if problems:
        raise ExperimentError(f"{path}: " + "; ".join(problems))
    return Experiment(
        name=data["name"],
        scenario=scenario,
        stack=registration.name,
        stack_file=registration.path,
        sim_time=registration.sim_time,
        perception=data.get("perception", "unet"),
        model=data.get("model", "flawed"),
        planner_config=data.get("planner_config", "planner.yaml"),
        episode_steps=steps,
        source=os.path.abspath(path),
        text=text,
        unet_backend=data.get("unet_backend", DEFAULT_UNET_BACKEND),
        textural_free=free,
        amplitude_free=ranges.get("amplitude_m"),
        hill_height_free=ranges.get("hill_height_m"),
        hill_positions_free=hill_positions,
        action_space=space,
        route_lateral_m=float(lateral),
    )
