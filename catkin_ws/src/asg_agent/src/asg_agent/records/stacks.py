"""Stacks under test, registered by a launch file (issue #55; docs/your-stack.md).

A stack is its launch file: its nodes, and a `<rosparam ns="stack">` block that tells the scene
worker and the campaigns what they need to know of it. worker.launch includes the file in the
worker's namespace (with all of its own arguments), so the block lands at `<worker>/stack/`:

    name: my_stack              # what campaigns and exports call it
    nodes: [planner, driver]    # the nodes that must be up; in lockstep, each acknowledges a run
    mode: free                  # lockstep (the stack answers every control tick) or free
    acks: false                 # true: its nodes acknowledge each run (the lockstep client does);
                                # false (free mode only): they need only be up
    command: twist              # twist (geometry_msgs/Twist on cmd_vel) or vehicle_command
    sim_time: true              # its nodes run on /clock, the worker's simulated time
    identity: [planner/speed]   # parameters that must be set on its workers; campaigns record them
    worker: {publish_points: true}   # scene worker parameters it needs (WORKER_KEYS)
    reference: depth            # optional (issue #67): the registration this stack is compared
                                # against, e.g. its last release (a name of stacks/ or a launch
                                # file's path, relative to this file's folder): attribution:=release
                                # re-runs every candidate on it and classes each failure a
                                # regression (only this stack fails) or shared

A file may hold several blocks under `if`/`unless` (the paper stack's nodes follow its
perception); they must agree on everything but `nodes` and `worker`. The two stacks of this
project are stacks/paper.launch and stacks/depth.launch, named `paper` and `depth`.

This module reads and checks a registration without ROS (xml and yaml); the scene worker reads
the same block from the parameter server (scene_worker_params.cpp).
"""

import os
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from typing import List, Tuple

import yaml

from asg_agent.paths import REPO

#: where the project's own registrations live (asg_bringup/stacks in an install space: builtin_dir)
BUILTIN_DIR = os.path.join(REPO, "stacks")


def builtin_dir() -> str:
    if os.path.isdir(BUILTIN_DIR):
        return BUILTIN_DIR
    import rospkg  # an install space: asg_bringup's share folder

    return os.path.join(rospkg.RosPack().get_path("asg_bringup"), "stacks")


KEYS = ("name", "nodes", "mode", "acks", "command", "sim_time", "identity", "worker", "reference")
MODES = ("lockstep", "free")
COMMANDS = ("vehicle_command", "twist")
#: the scene worker parameters a registration may set (docs/simulator.md)
WORKER_KEYS = (
    "publish_points",
    "points_stride",
    "publish_labels",
    "labels_node",
    "publish_map_odom",
    "publish_clock",
    "realtime_factor",
)
#: what every block of one file must agree on
SHARED = ("name", "mode", "acks", "command", "sim_time", "identity", "reference")


class RegistrationError(ValueError):
    """A stack registration that cannot be used, naming the file and what is wrong."""


@dataclass
class Registration:
    name: str
    path: str  #: the launch file, absolute
    mode: str = "lockstep"
    acks: bool = True
    command: str = "vehicle_command"
    sim_time: bool = False
    identity: List[str] = field(default_factory=list)
    nodes: List[Tuple[str, ...]] = field(default_factory=list)  #: each block's node list
    reference: str = ""  #: the registration it is compared against, as written ("" for none)

    @property
    def reference_file(self) -> str:
        """The reference registration's launch file (absolute), "" for none; RegistrationError if
        it names no registration."""
        if not self.reference:
            return ""
        path = resolve(self.reference, os.path.dirname(self.path))
        if path == self.path:
            raise RegistrationError(f"{self.path}: reference: {self.reference!r} is this registration itself")
        return path

    @property
    def builtin(self) -> bool:
        return os.path.dirname(self.path) == os.path.realpath(builtin_dir())


def resolve(stack: str, base_dir: str = "") -> str:
    """The registration file of `stack`: a name of stacks/ (paper, depth) or the path of a launch
    file (relative to `base_dir`, an experiment file's folder). RegistrationError if none."""
    if not isinstance(stack, str) or not stack:
        raise RegistrationError(f"stack: {stack!r}, must be a stack's name or the path of its launch file")
    if not stack.endswith(".launch"):
        path = os.path.join(builtin_dir(), stack + ".launch")
        if not os.path.isfile(path):
            known = sorted(f[: -len(".launch")] for f in os.listdir(builtin_dir()) if f.endswith(".launch"))
            raise RegistrationError(
                f"stack: {stack!r} is not a registered stack ({', '.join(known)}), nor the path of a .launch file"
            )
        return os.path.realpath(path)
    path = os.path.expanduser(stack)
    if not os.path.isabs(path):
        path = os.path.join(base_dir or os.getcwd(), path)
    if not os.path.isfile(path):
        raise RegistrationError(f"stack: {stack}: no such launch file ({path})")
    return os.path.realpath(path)


def read(path: str) -> Registration:
    """The registration in the launch file `path`, checked."""
    try:
        root = ET.parse(path).getroot()
    except (OSError, ET.ParseError) as e:
        raise RegistrationError(f"{path}: cannot read it as a launch file ({e})") from None
    blocks = [el for el in root.iter("rosparam") if (el.get("ns") or "").strip("/") == "stack"]
    if not blocks:
        raise RegistrationError(
            f'{path}: no <rosparam ns="stack"> block: a stack registers itself with one (docs/your-stack.md)'
        )
    parsed = [_block(path, i, b) for i, b in enumerate(blocks)]
    first = parsed[0]
    for i, p in enumerate(parsed[1:], 1):
        differ = [k for k in SHARED if p[k] != first[k]]
        if differ:
            raise RegistrationError(f"{path}: stack block {i + 1} differs from the first in {', '.join(differ)}")
    return Registration(
        name=first["name"],
        path=os.path.realpath(path),
        mode=first["mode"],
        acks=first["acks"],
        command=first["command"],
        sim_time=first["sim_time"],
        identity=list(first["identity"]),
        nodes=[tuple(p["nodes"]) for p in parsed],
        reference=first["reference"],
    )


def load(stack: str, base_dir: str = "") -> Registration:
    return read(resolve(stack, base_dir))


def _block(path: str, i: int, el) -> dict:
    where = f"{path}: stack block {i + 1}"
    if el.get("subst_value", "").lower() == "true" or "$(" in (el.text or ""):
        raise RegistrationError(f"{where}: substitutions ($(...)) are not allowed in a registration")
    try:
        d = yaml.safe_load(el.text or "") or {}
    except yaml.YAMLError as e:
        raise RegistrationError(f"{where}: not valid YAML ({e})") from None
    if not isinstance(d, dict):
        raise RegistrationError(f"{where}: must be a mapping")
    problems = [f"{k}: unknown key (allowed: {', '.join(KEYS)})" for k in d if k not in KEYS]
    if not isinstance(d.get("name"), str) or not d.get("name", "").strip():
        problems.append("name: required, a non-empty string")
    nodes = d.get("nodes")
    if not isinstance(nodes, list) or not nodes or not all(isinstance(n, str) and n for n in nodes):
        problems.append("nodes: required, a non-empty list of node names")
    d.setdefault("mode", "lockstep")
    if d["mode"] not in MODES:
        problems.append(f"mode: {d['mode']!r}, must be lockstep or free")
    d.setdefault("acks", True)
    if not isinstance(d["acks"], bool):
        problems.append(f"acks: {d['acks']!r}, must be true or false")
    elif not d["acks"] and d["mode"] == "lockstep":
        problems.append("acks: false needs mode: free (in lockstep the stack's client acknowledges each run)")
    d.setdefault("command", "vehicle_command")
    if d["command"] not in COMMANDS:
        problems.append(f"command: {d['command']!r}, must be vehicle_command or twist")
    d.setdefault("sim_time", False)
    if not isinstance(d["sim_time"], bool):
        problems.append(f"sim_time: {d['sim_time']!r}, must be true or false")
    d.setdefault("identity", [])
    if not isinstance(d["identity"], list) or not all(isinstance(n, str) and n for n in d["identity"]):
        problems.append("identity: a list of parameter names (relative to the worker's namespace)")
    d.setdefault("reference", "")
    if not isinstance(d["reference"], str):
        problems.append(f"reference: {d['reference']!r}, must be a stack's name or the path of its launch file")
    worker = d.setdefault("worker", {})
    if not isinstance(worker, dict):
        problems.append("worker: a mapping of scene worker parameters")
    else:
        problems += [
            f"worker: {k}: not a scene worker parameter a stack sets ({', '.join(WORKER_KEYS)})"
            for k in worker
            if k not in WORKER_KEYS
        ]
    if problems:
        raise RegistrationError(f"{where}: " + "; ".join(problems))
    return d
