"""Parameter tables for the project's Python nodes (issue #56; no ROS): each node lists its
parameters once, with kind, unit, default, allowed values and meaning; the node reads them through
its table (a bad value names the parameter and what is allowed) and docs/ quotes the table's
Markdown (tests/test_node_parameters.py holds them equal). The planner's C++ table is
asg_planner/parameters.hpp."""

import math
from dataclasses import dataclass
from typing import Any, Callable, Dict, List, Optional, Sequence


@dataclass(frozen=True)
class Param:
    name: str  #: relative to the node's private namespace (~), e.g. "grid/cell"
    kind: type  #: float, int, bool or str
    default: Any
    unit: str  #: "-" for none
    doc: str
    lo: Optional[float] = None  #: inclusive bounds of a number (None: unbounded)
    hi: Optional[float] = None
    choices: Optional[Sequence[str]] = None  #: allowed strings
    rule: Optional[Callable[[Any], bool]] = None  #: a further condition, said by `rule_text`
    rule_text: str = ""

    def allowed(self) -> str:
        if self.kind is bool:
            return "true or false"
        if self.choices is not None:
            return " or ".join(f"'{c}'" if c else "empty" for c in self.choices)
        if self.kind is str:
            return "a string" + (f", {self.rule_text}" if self.rule_text else "")
        kind = "an integer" if self.kind is int else "a number"
        lo = "-inf" if self.lo is None else f"{self.lo:g}"
        hi = "inf" if self.hi is None else f"{self.hi:g}"
        return f"{kind} in [{lo}, {hi}]" + (f", {self.rule_text}" if self.rule_text else "")

    def convert(self, raw) -> Any:
        """`raw` as this parameter's kind, or ValueError naming the parameter and what is allowed."""
        bad = ValueError(f"~{self.name} = {raw!r}: must be {self.allowed()}")
        if self.kind is bool:
            if not isinstance(raw, bool):
                raise bad
            return raw
        if self.kind is str:
            if not isinstance(raw, str) or (self.choices is not None and raw not in self.choices):
                raise bad
            value = raw
        else:
            if isinstance(raw, bool) or not isinstance(raw, (int, float)):
                raise bad
            if self.kind is int and (not float(raw).is_integer()):
                raise bad
            value = self.kind(raw)
            if not math.isfinite(value) or (self.lo is not None and value < self.lo):
                raise bad
            if self.hi is not None and value > self.hi:
                raise bad
        if self.rule is not None and not self.rule(value):
            raise bad
        return value


def read(table: List[Param], get: Callable[[str, Any], Any]) -> Dict[str, Any]:
    """{name: value} of every parameter of `table`; `get(name, default)` reads one (a node passes
    `lambda n, d: rospy.get_param("~" + n, d)`). Raises ValueError naming each bad one."""
    out, problems = {}, []
    for p in table:
        try:
            out[p.name] = p.convert(get(p.name, p.default))
        except ValueError as e:
            problems.append(str(e))
    if problems:
        raise ValueError("; ".join(problems))
    return out


def markdown(table: List[Param]) -> str:
    """The table as docs/ shows it."""

    def shown(v):
        if isinstance(v, bool):
            return "true" if v else "false"
        return "empty" if v == "" else str(v)

    rows = ["| parameter | unit | default | allowed | meaning |", "|---|---|---|---|---|"]
    rows += [f"| `~{p.name}` | {p.unit} | {shown(p.default)} | {p.allowed()} | {p.doc} |" for p in table]
    return "\n".join(rows)


#: The lockstep client's own parameter, in the node that uses it: the Python client
#: (asg_lockstep.ros.LockstepClient) reads this table, the C++ one (ros/lockstep_client.hpp) its
#: generated header (include/asg_lockstep/client_params.hpp, `python3 -m asg_lockstep.cpp_params`).
CLIENT = [
    Param(
        "lockstep",
        bool,
        True,
        "-",
        "false: run free (acknowledgements only, no ticks); unset: the stack's registration decides "
        "(`stack/mode`), else true",
    ),
]

#: The stand-in stack of the scene worker's tests and benchmarks (asg_sim/scripts/scripted_driver;
#: docs/simulator.md quotes this table). It reads its parameters through this table, so that
#: `~throttle: true` is refused by name instead of driving at float(True) = 1.0 (issue #80).
SCRIPTED_DRIVER = [
    Param(
        "mode",
        str,
        "constant",
        "-",
        "constant: the fixed command below; goal: steer towards the goal at the scenario's speed, from "
        "the odometry of the tick's own stamp; silent: acknowledge, never answer (to test the timeout)",
        choices=("constant", "goal", "silent"),
    ),
    Param("throttle", float, 0.5, "-", "mode constant: the throttle of every command", 0.0, 1.0),
    Param("steering", float, 0.0, "-", "mode constant: the steering of every command (left positive)", -1.0, 1.0),
    Param("brake", float, 0.0, "-", "mode constant: the brake of every command", 0.0, 1.0),
    Param("ack_name", str, "", "-", "the name its acknowledgements carry (empty: the node's name)"),
]


def registered_lockstep(mode) -> Optional[bool]:
    """What a stack registration's `stack/mode` says of lockstep: None when unset, True for
    'lockstep', False for 'free'; anything else is refused by name (issue #80: another string ran
    free without a word). The C++ client words it the same (client_settings.hpp)."""
    if mode is None:
        return None
    if isinstance(mode, str) and mode in ("lockstep", "free"):
        return mode == "lockstep"
    shown = (
        f"'{mode}'" if isinstance(mode, str) else ("true" if mode is True else "false" if mode is False else str(mode))
    )
    raise ValueError(f"stack/mode = {shown}: must be 'lockstep' or 'free'")
