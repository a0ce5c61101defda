"""Scenario file format: schema, loader and validator (no ROS imports).

A scenario file is YAML whose keys map one to one onto ``asg_msgs/SceneDescription`` (plus a
few file-level keys: ``format_version``, ``name``, ``scenario_id``, ``record_labels``). Every
tool loads scenarios through :func:`load_scenario` or :func:`validate_scenario`, which return a
canonical dict (every field present, with its documented type) or raise :class:`ScenarioError`
listing every problem found, each naming the field, the value and what is allowed.
"""

import math
from dataclasses import dataclass
from typing import Any, List, Optional, Tuple

import yaml

from .catalogue import MESHES, TRAVERSABLE_HEIGHT, VEHICLE_HALF_WIDTH

FORMAT_VERSION = 1

# The scene budget (docs/scenario-format.md): what one worker can build and run in bounded memory
# and time. asg_sim's C++ validator (scene.hpp) enforces the same numbers.
#: Most obstacle instances one scene may hold (memory and render-time bound).
MAX_OBSTACLES = 512
#: [m] largest side of the nominal square and largest border.
MAX_LANDSCAPE_SIZE = 1000.0
MAX_BORDER = 1000.0
#: [-] ground cells per side including the border: subdivisions x (size + 2 border) / size.
MAX_GROUND_CELLS_PER_SIDE = 2048.0
#: [s] sim_timeout is required and finite, so every run ends.
MAX_SIM_TIMEOUT = 3600.0
#: Terrain (asg_sim terrain.hpp holds the same numbers): most hills and ditches in one scene, and
#: the steepness bounds amplitude_m <= wavelength_m / 10 and |height_m| <= radius_m / 2.
MAX_HILLS = 32
MAX_AMPLITUDE_PER_WAVELENGTH = 0.1
MAX_HILL_HEIGHT_PER_RADIUS = 0.5


@dataclass(frozen=True)
class Field:
    """One scalar field of the format."""

    key: str
    kind: type  #: float, int, bool or str
    unit: str
    lo: Optional[float]  #: inclusive lower bound (None: unbounded)
    hi: Optional[float]  #: inclusive upper bound (None: unbounded)
    doc: str
    default: Any = None  #: None: required
    disable_value: Optional[float] = None  #: a value outside [lo, hi] that is also allowed

    def allowed(self) -> str:
        if self.kind is bool:
            return "true or false"
        if self.kind is str:
            return "a string"
        lo = "-inf" if self.lo is None else f"{self.lo:g}"
        hi = "inf" if self.hi is None else f"{self.hi:g}"
        text = f"{'an integer' if self.kind is int else 'a finite number'} in [{lo}, {hi}]"
        if self.disable_value is not None:
            text += f", or {self.disable_value:g} to disable"
        return text


TOP_FIELDS = [
    Field("format_version", int, "-", 1, 1, "Version of this format.", FORMAT_VERSION),
    Field("name", str, "-", None, None, "Free-form name shown in logs and reports.", ""),
    Field(
        "scenario_id", int, "-", 1, 2**32 - 1, "Id announced to the autonomy stack; tools assign one when absent.", 1
    ),
    Field(
        "record_labels",
        bool,
        "-",
        None,
        None,
        "Render ground-truth labels during the run (needed for per-obstacle visibility).",
        True,
    ),
]

LANDSCAPE_FIELDS = [
    Field("size", float, "m", 1.0, MAX_LANDSCAPE_SIZE, "Side of the nominal square [0, size]^2."),
    Field("subdivisions", int, "-", 1, 4096, "Ground mesh cells per side.", 64),
    Field(
        "border",
        float,
        "m",
        0.0,
        MAX_BORDER,
        "Ground rendered around the nominal square (horizon, leaving the area).",
        50.0,
    ),
]

TERRAIN_FIELDS = [
    Field(
        "amplitude_m",
        float,
        "m",
        0.0,
        5.0,
        "Largest height of the rolling ground (the mean of 3 seeded plane waves); 0: none. "
        "At most wavelength_m / 10.",
        0.0,
    ),
    Field(
        "wavelength_m",
        float,
        "m",
        5.0,
        1000.0,
        "Typical wavelength of the rolling ground (each wave's within a factor sqrt 2 of it).",
        40.0,
    ),
    Field("seed", int, "-", 0, 2**32 - 1, "Seed of the waves' directions, wavelengths and phases.", 0),
]

HILL_FIELDS = [
    Field("x", float, "m", None, None, "Centre, within [0, landscape.size]."),
    Field("y", float, "m", None, None, "Centre, within [0, landscape.size]."),
    Field("radius_m", float, "m", 1.0, 200.0, "Where the raised-cosine bump meets the ground around it."),
    Field(
        "height_m",
        float,
        "m",
        -10.0,
        10.0,
        "Height at the centre; negative: a ditch. Its absolute value at most radius_m / 2.",
    ),
]

INSTANCE_FIELDS = [
    Field("visible", bool, "-", None, None, "false: the instance is not placed.", True),
    Field("cast_shadow", bool, "-", None, None, "false: rendered without a shadow.", True),
    Field("x", float, "m", None, None, "Position, within [0, landscape.size]."),
    Field("y", float, "m", None, None, "Position, within [0, landscape.size]."),
    Field("yaw", float, "rad", -2 * math.pi, 2 * math.pi, "Rotation about z.", 0.0),
    Field("scale", float, "-", 0.01, 100.0, "Uniform scale of the mesh (0 is not allowed).", 1.0),
]

TEXTURAL_FIELDS = [
    Field(
        "sun_inclination_deg",
        float,
        "deg",
        0.0,
        90.0,
        "Sun elevation above the horizon (90: overhead, no visible shadows).",
    ),
    Field(
        "sun_yaw_deg",
        float,
        "deg",
        -360.0,
        360.0,
        "Direction the sunlight comes from, counter-clockwise from map +x.",
        0.0,
    ),
    Field("ground_texture_seed", int, "-", 0, 2**32 - 1, "Seed of the ground texture.", 0),
    Field(
        "fog_visibility_m",
        float,
        "m",
        0.0,
        100000.0,
        "Fog: the distance at which a surface keeps 5 % of its contrast (transmittance exp(-3 d / V)); "
        "nothing beyond it is labelled visible. 0: no fog.",
        0.0,
    ),
    Field(
        "cloud_cover",
        float,
        "-",
        0.0,
        1.0,
        "0 (clear sky) .. 1 (overcast): direct sunlight down to 20 %, more diffuse light, weaker shadows, grey sky.",
        0.0,
    ),
]

OPERATIONAL_FIELDS = [
    Field("start_x", float, "m", None, None, "Vehicle start, within the landscape."),
    Field("start_y", float, "m", None, None, "Vehicle start, within the landscape."),
    Field("start_yaw", float, "rad", -2 * math.pi, 2 * math.pi, "Start heading.", 0.0),
    Field("goal_x", float, "m", None, None, "Goal, within the landscape."),
    Field("goal_y", float, "m", None, None, "Goal, within the landscape."),
    Field("goal_radius", float, "m", 0.1, 1000.0, "Success within this distance of the goal.", 11.0),
    Field("safety_radius", float, "m", 0.0, 1000.0, "Obstacles closer than this to start or goal are removed.", 11.0),
    Field("speed", float, "m/s", 0.1, 30.0, "Tracking speed of the vehicle under test.", 5.0),
    Field(
        "sim_timeout",
        float,
        "s",
        0.1,
        MAX_SIM_TIMEOUT,
        "Simulated time limit (required to be finite: every run ends).",
        120.0,
    ),
    Field("idle_timeout", float, "s", 0.1, MAX_SIM_TIMEOUT, "Idling time limit.", 10.0, -1.0),
    Field("stuck_timeout", float, "s", 0.1, MAX_SIM_TIMEOUT, "Stuck time limit.", 10.0, -1.0),
    Field("max_roll_deg", float, "deg", 1.0, 180.0, "Roll beyond this ends the run (FLIPPED).", 70.0),
    Field("max_pitch_deg", float, "deg", 1.0, 180.0, "Pitch beyond this ends the run.", 70.0),
    Field("allow_collisions", bool, "-", None, None, "Contact with obstacles does not end the run.", False),
]

#: How a run ends: (name, value, meaning), declared once. RunScenario.action's constants, the C++
#: enum (asg_sim/scene_schema.hpp, generated from this file) and the agent's failure set follow it
#: (tests/test_scenario_schema.py holds the action file to it).
TERMINATIONS = [
    ("SUCCESS", 0, "within goal_radius of the goal"),
    ("COLLISION", 1, "contact with an obstacle (unless allow_collisions)"),
    ("FLIPPED", 2, "roll or pitch beyond max_roll_deg / max_pitch_deg"),
    ("SIM_TIMEOUT", 3, "sim_timeout reached"),
    ("IDLING_TIMEOUT", 4, "no command moved the vehicle for idle_timeout"),
    ("STUCK_TIMEOUT", 5, "commanded but not moving for stuck_timeout"),
    ("OUT_OF_BOUNDS", 6, "left the landscape"),
    ("ERROR", 7, "the run could not be completed (the stack failed, a bad scene)"),
]
#: The terminations that are a failure of the stack under test (not SUCCESS, not ERROR).
FAILED_TERMINATIONS = tuple(name for name, _, _ in TERMINATIONS if name not in ("SUCCESS", "ERROR"))

#: The keys of each mapping of the format that are not scalar fields of SECTIONS: the sections and
#: lists nested in it, and the layout's mesh name. With a section's fields, the keys that mapping may
#: hold (allowed_keys); asg_sim's C++ loader reads its key lists from the header generated from
#: both (cpp_schema.py), so a key is added here once.
NESTED_KEYS = {
    "": ("structural", "textural", "operational"),
    "structural": ("landscape", "layouts", "terrain"),
    "structural.terrain": ("hills",),
    "structural.layouts[i]": ("mesh_name", "instances"),
}

#: Sections of the format, for docs and iteration: (path, fields).
SECTIONS = [
    ("", TOP_FIELDS),
    ("structural.landscape", LANDSCAPE_FIELDS),
    ("structural.terrain", TERRAIN_FIELDS),
    ("structural.terrain.hills[k]", HILL_FIELDS),
    ("structural.layouts[i].instances[j]", INSTANCE_FIELDS),
    ("textural", TEXTURAL_FIELDS),
    ("operational", OPERATIONAL_FIELDS),
]


def allowed_keys(path: str) -> List[str]:
    """Every key the mapping at `path` (a SECTIONS or NESTED_KEYS path) may hold, sorted."""
    fields = dict(SECTIONS).get(path, [])
    return sorted([f.key for f in fields] + list(NESTED_KEYS.get(path, ())))


class ScenarioError(ValueError):
    """A scenario is malformed. ``problems`` lists (field path, message) pairs."""

    def __init__(self, problems: List[Tuple[str, str]], source: str = "scenario"):
        self.problems = problems
        self.source = source
        lines = [f"{source}: {len(problems)} problem(s):"]
        lines += [f"  - {path}: {msg}" for path, msg in problems]
        super().__init__("\n".join(lines))


class _Checker:
    def __init__(self):
        self.problems: List[Tuple[str, str]] = []

    def fail(self, path: str, msg: str):
        self.problems.append((path, msg))

    def mapping(self, value, path) -> dict:
        if value is None:
            self.fail(path, "missing section (a mapping is required)")
            return {}
        if not isinstance(value, dict):
            self.fail(path, f"= {value!r}: must be a mapping, got {type(value).__name__}")
            return {}
        return value

    def fields(self, data: dict, fields: List[Field], path: str) -> dict:
        out = {}
        known = {f.key for f in fields}
        for key in data:
            if key not in known:
                self.fail(_join(path, str(key)), f"unknown field (allowed: {', '.join(sorted(known))})")
        for f in fields:
            out[f.key] = self.scalar(data, f, path)
        return out

    def scalar(self, data: dict, f: Field, path: str):
        where = _join(path, f.key)
        if f.key not in data:
            if f.default is None:
                self.fail(where, f"missing required field ({f.allowed()}, unit {f.unit})")
            return f.default
        v = data[f.key]
        if f.kind is bool:
            if not isinstance(v, bool):
                self.fail(where, f"= {v!r}: wrong type {type(v).__name__}, must be true or false")
                return f.default
            return v
        if f.kind is str:
            if not isinstance(v, str):
                self.fail(where, f"= {v!r}: wrong type {type(v).__name__}, must be a string")
                return f.default
            return v
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            self.fail(where, f"= {v!r}: wrong type {type(v).__name__}, must be {f.allowed()}")
            return f.default
        if f.kind is int and (isinstance(v, float) and not v.is_integer()):
            self.fail(where, f"= {v!r}: must be {f.allowed()}")
            return f.default
        if isinstance(v, float) and not math.isfinite(v):
            self.fail(where, f"= {v!r}: must be {f.allowed()}")
            return f.default
        try:
            v = f.kind(v)
        except OverflowError:  # an integer too large for a float
            self.fail(where, f"= {_short(v)}: out of range, must be {f.allowed()} [{f.unit}]")
            return f.default
        if f.disable_value is not None and v == f.disable_value:
            return v
        if (f.lo is not None and v < f.lo) or (f.hi is not None and v > f.hi):
            self.fail(where, f"= {_short(v)}: out of range, must be {f.allowed()} [{f.unit}]")
            return f.default
        return v


def _short(v) -> str:
    text = repr(v)
    return text if len(text) <= 40 else text[:20] + "..." + f" ({len(text)} digits)"


def _join(path: str, key: str) -> str:
    return f"{path}.{key}" if path else key


def validate_scenario(data: Any, source: str = "scenario") -> dict:
    """Check a parsed scenario and return its canonical form.

    Raises:
        ScenarioError: listing every problem (field path, value, what is allowed).
    """
    c = _Checker()
    if not isinstance(data, dict):
        raise ScenarioError([("<root>", f"must be a mapping of sections, got {type(data).__name__}")], source)
    _only(c, data, "")
    out = {f.key: c.scalar(data, f, "") for f in TOP_FIELDS}

    structural = c.mapping(data.get("structural"), "structural")
    _only(c, structural, "structural")
    landscape = c.fields(
        c.mapping(structural.get("landscape"), "structural.landscape"), LANDSCAPE_FIELDS, "structural.landscape"
    )
    # Absent: the flat ground. Null is refused, as the simulator's loader does.
    raw_terrain = c.mapping(structural.get("terrain", {}), "structural.terrain")
    terrain = c.fields({k: v for k, v in raw_terrain.items() if k != "hills"}, TERRAIN_FIELDS, "structural.terrain")
    raw_hills = raw_terrain.get("hills", [])
    if not isinstance(raw_hills, list):
        c.fail("structural.terrain.hills", f"= {raw_hills!r}: must be a list of hills")
        raw_hills = []
    if len(raw_hills) > MAX_HILLS:
        c.fail("structural.terrain.hills", f"{len(raw_hills)} hills: at most {MAX_HILLS} allowed")
        raw_hills = []
    terrain["hills"] = [
        c.fields(c.mapping(h, f"structural.terrain.hills[{k}]"), HILL_FIELDS, f"structural.terrain.hills[{k}]")
        for k, h in enumerate(raw_hills)
    ]
    layouts = []
    raw_layouts = structural.get("layouts", [])
    if not isinstance(raw_layouts, list):
        c.fail("structural.layouts", f"= {raw_layouts!r}: must be a list of layouts")
        raw_layouts = []
    total = 0
    for i, raw in enumerate(raw_layouts):
        lpath = f"structural.layouts[{i}]"
        raw = c.mapping(raw, lpath)
        _only(c, raw, "structural.layouts[i]", lpath)
        mesh = raw.get("mesh_name")
        if mesh is None:
            c.fail(f"{lpath}.mesh_name", f"missing required field (one of {', '.join(sorted(MESHES))})")
        elif not isinstance(mesh, str):
            c.fail(f"{lpath}.mesh_name", f"= {mesh!r}: wrong type {type(mesh).__name__}, must be a string")
            mesh = None
        elif mesh not in MESHES:
            c.fail(f"{lpath}.mesh_name", f"= {mesh!r}: unknown mesh (one of {', '.join(sorted(MESHES))})")
        insts = raw.get("instances", [])
        if not isinstance(insts, list):
            c.fail(f"{lpath}.instances", f"= {insts!r}: must be a list of instances")
            insts = []
        total += len(insts)
        layout = {"mesh_name": mesh, "instances": []}
        for j, inst in enumerate(insts):
            ipath = f"{lpath}.instances[{j}]"
            layout["instances"].append(c.fields(c.mapping(inst, ipath), INSTANCE_FIELDS, ipath))
        layouts.append(layout)
    if total > MAX_OBSTACLES:
        c.fail("structural.layouts", f"{total} obstacle instances: at most {MAX_OBSTACLES} allowed")
    out["structural"] = {"landscape": landscape, "terrain": terrain, "layouts": layouts}
    out["textural"] = c.fields(c.mapping(data.get("textural"), "textural"), TEXTURAL_FIELDS, "textural")
    out["operational"] = c.fields(c.mapping(data.get("operational"), "operational"), OPERATIONAL_FIELDS, "operational")
    if not c.problems:
        _check_geometry(out, c)
    if c.problems:
        raise ScenarioError(c.problems, source)
    return out


def _only(c: "_Checker", mapping: dict, path: str, where: Optional[str] = None):
    """A problem for each key of `mapping` that the format's `path` does not hold (`where`: the
    path as the problem names it, with list indices)."""
    allowed = allowed_keys(path)
    prefix = f"{where if where is not None else path}." if (where or path) else ""
    for key in mapping:
        if key not in allowed:
            c.fail(f"{prefix}{key}", f"unknown field (allowed: {', '.join(allowed)})")


def _check_geometry(s: dict, c: _Checker):
    land = s["structural"]["landscape"]
    size = land["size"]
    op = s["operational"]
    cells = land["subdivisions"] * (size + 2.0 * land["border"]) / size
    if cells > MAX_GROUND_CELLS_PER_SIDE:
        c.fail(
            "structural.landscape.subdivisions",
            f"= {land['subdivisions']} gives {math.ceil(cells)} ground cells per side with the "
            f"border: at most {MAX_GROUND_CELLS_PER_SIDE:g} (subdivisions x (size + 2 border) / size)",
        )

    def inside(path, x, y):
        ok = True
        for axis, v in (("x", x), ("y", y)):
            if not 0.0 <= v <= size:
                c.fail(f"{path}{axis}", f"= {v!r}: outside the landscape, must be in [0, {size:g}] m")
                ok = False
        return ok

    inside("operational.start_", op["start_x"], op["start_y"])
    inside("operational.goal_", op["goal_x"], op["goal_y"])
    terrain = s["structural"]["terrain"]
    if terrain["amplitude_m"] > MAX_AMPLITUDE_PER_WAVELENGTH * terrain["wavelength_m"]:
        c.fail(
            "structural.terrain.amplitude_m",
            f"= {terrain['amplitude_m']!r}: too steep for wavelength_m {terrain['wavelength_m']:g}, "
            "must be at most wavelength_m / 10 m",
        )
    for k, hill in enumerate(terrain["hills"]):
        hpath = f"structural.terrain.hills[{k}]."
        inside(hpath, hill["x"], hill["y"])
        if abs(hill["height_m"]) > MAX_HILL_HEIGHT_PER_RADIUS * hill["radius_m"]:
            c.fail(
                f"{hpath}height_m",
                f"= {hill['height_m']!r}: too steep for radius_m {hill['radius_m']:g}, "
                "|height_m| must be at most radius_m / 2 m",
            )
    for i, layout in enumerate(s["structural"]["layouts"]):
        mesh = MESHES[layout["mesh_name"]]
        for j, inst in enumerate(layout["instances"]):
            ipath = f"structural.layouts[{i}].instances[{j}]."
            if not inside(ipath, inst["x"], inst["y"]) or not inst["visible"]:
                continue
            if mesh.height * inst["scale"] <= TRAVERSABLE_HEIGHT:
                continue
            d_start = math.hypot(inst["x"] - op["start_x"], inst["y"] - op["start_y"])
            if d_start < op["safety_radius"]:
                continue  # the worker removes it
            reach = mesh.collision_radius * inst["scale"] + VEHICLE_HALF_WIDTH
            if d_start < reach:
                c.fail(
                    ipath[:-1],
                    f"the start pose ({op['start_x']:g}, {op['start_y']:g}) is "
                    f"inside this {layout['mesh_name']} (distance {d_start:.2f} m < {reach:.2f} m "
                    f"and safety_radius {op['safety_radius']:g} m does not remove it)",
                )


def load_scenario(path: str) -> dict:
    """Read and validate a scenario YAML file.

    Raises:
        ScenarioError: the file is unreadable, not YAML, or not a valid scenario.
    """
    try:
        with open(path, "r", encoding="utf-8") as f:
            text = f.read()
    except OSError as e:
        raise ScenarioError([("<file>", f"cannot read: {e.strerror}")], str(path)) from None
    except UnicodeDecodeError as e:
        raise ScenarioError(
            [("<file>", f"not UTF-8 text (byte 0x{e.object[e.start]:02x} at offset {e.start})")], str(path)
        ) from None
    return parse_scenario(text, str(path))


class _StrictLoader(yaml.SafeLoader):
    """safe_load that refuses a key given twice in one mapping (PyYAML would keep the last one
    silently, the simulator's loader the first: neither is what the author meant)."""


def _no_duplicates(loader, node, deep=False):
    seen = set()
    for key_node, _ in node.value:
        key = loader.construct_object(key_node, deep=True)
        try:
            hash(key)
        except TypeError:
            continue  # an unhashable key: construct_mapping reports it
        if key in seen:
            raise yaml.constructor.ConstructorError(
                None, None, f"key {key!r} is given twice in one mapping", key_node.start_mark
            )
        seen.add(key)
    return loader.construct_mapping(node, deep=deep)


_StrictLoader.add_constructor(yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG, _no_duplicates)


def strict_yaml_load(text: str):
    """yaml.safe_load, but a key given twice in one mapping is a yaml.YAMLError."""
    return yaml.load(text, Loader=_StrictLoader)


def parse_scenario(text: str, source: str = "scenario") -> dict:
    """Parse YAML text and validate it (see :func:`validate_scenario`)."""
    try:
        data = strict_yaml_load(text)
    except yaml.YAMLError as e:
        mark = getattr(e, "problem_mark", None)
        where = f"line {mark.line + 1}, column {mark.column + 1}" if mark else "?"
        raise ScenarioError([("<yaml>", f"not valid YAML at {where}: {getattr(e, 'problem', e)}")], source) from None
    except RecursionError:
        raise ScenarioError([("<yaml>", "nested too deeply to be a scenario")], source) from None
    return validate_scenario(data, source)


def dump_scenario(scenario: dict) -> str:
    """Canonical YAML text of a validated scenario."""
    return yaml.safe_dump(scenario, sort_keys=False, default_flow_style=None)
