"""Scenario schema and validator: the shipped files load, every kind of bad input is named."""

import copy
import math
import os

import pytest
import yaml

from asg_scenario import ScenarioError, dump_scenario, load_scenario, parse_scenario, validate_scenario

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", "..", ".."))
SCENARIOS = os.path.join(REPO, "scenarios")


def exp1():
    return load_scenario(os.path.join(SCENARIOS, "exp1.yaml"))


def problems_of(data):
    with pytest.raises(ScenarioError) as info:
        validate_scenario(data, "test")
    return info.value


@pytest.mark.parametrize("k,size,n", [(1, 100, 8), (2, 200, 16), (3, 200, 32), (4, 100, 8)])
def test_paper_experiments_load(k, size, n):
    s = load_scenario(os.path.join(SCENARIOS, f"exp{k}.yaml"))
    assert s["structural"]["landscape"]["size"] == size
    assert sum(len(l["instances"]) for l in s["structural"]["layouts"]) == n
    assert s["operational"]["goal_radius"] == 11.0 and s["operational"]["safety_radius"] == 11.0
    assert s["operational"]["speed"] == (2.5 if k == 4 else 5.0)


def test_canonical_round_trip():
    s = exp1()
    assert parse_scenario(dump_scenario(s)) == s


def test_defaults_fill_optional_fields():
    s = exp1()
    raw = yaml.safe_load(dump_scenario(s))
    del raw["operational"]["idle_timeout"]
    del raw["structural"]["layouts"][0]["instances"][0]["scale"]
    out = validate_scenario(raw)
    assert out["operational"]["idle_timeout"] == 10.0
    assert out["structural"]["layouts"][0]["instances"][0]["scale"] == 1.0


def test_disable_value_allowed():
    raw = exp1()
    raw["operational"]["idle_timeout"] = -1
    assert validate_scenario(raw)["operational"]["idle_timeout"] == -1
    raw["operational"]["sim_timeout"] = -1  # every run must end: sim_timeout has no disable value
    assert "operational.sim_timeout" in [p for p, _ in problems_of(raw).problems]


@pytest.mark.parametrize(
    "mutate,field,words",
    [
        (lambda s: s["operational"].__setitem__("start_x", float("nan")), "operational.start_x", "nan"),
        (lambda s: s["operational"].__setitem__("goal_y", math.inf), "operational.goal_y", "inf"),
        (lambda s: s["operational"].__setitem__("start_x", 150.0), "operational.start_x", "outside the landscape"),
        (
            lambda s: s["structural"]["layouts"][0]["instances"][1].__setitem__("x", -3.0),
            "structural.layouts[0].instances[1].x",
            "outside the landscape",
        ),
        (
            lambda s: s["structural"]["layouts"][1]["instances"][0].__setitem__("scale", -1.0),
            "structural.layouts[1].instances[0].scale",
            "out of range",
        ),
        (
            lambda s: s["structural"]["layouts"][0].__setitem__("mesh_name", "oak"),
            "structural.layouts[0].mesh_name",
            "unknown mesh",
        ),
        (lambda s: s["operational"].pop("goal_x"), "operational.goal_x", "missing required"),
        (lambda s: s.pop("textural"), "textural", "missing section"),
        (lambda s: s["operational"].__setitem__("speed", "fast"), "operational.speed", "wrong type"),
        (lambda s: s["operational"].__setitem__("allow_collisions", 1), "operational.allow_collisions", "wrong type"),
        (
            lambda s: s["structural"]["landscape"].__setitem__("subdivisions", 2.5),
            "structural.landscape.subdivisions",
            "an integer",
        ),
        (
            lambda s: s["textural"].__setitem__("sun_inclination_deg", 120.0),
            "textural.sun_inclination_deg",
            "out of range",
        ),
        (lambda s: s["operational"].__setitem__("idle_timeout", -5.0), "operational.idle_timeout", "-1 to disable"),
        (lambda s: s["operational"].__setitem__("colour", "red"), "operational.colour", "unknown field"),
        (lambda s: s["structural"].__setitem__("layouts", {"a": 1}), "structural.layouts", "list"),
    ],
)
def test_bad_input_names_field_value_and_rule(mutate, field, words):
    raw = copy.deepcopy(exp1())
    mutate(raw)
    err = problems_of(raw)
    paths = [p for p, _ in err.problems]
    assert field in paths, err
    msg = dict(err.problems)[field]
    assert words in msg.lower(), msg
    assert field in str(err)


def test_start_inside_obstacle():
    raw = exp1()
    raw["operational"]["safety_radius"] = 0.0
    tree = raw["structural"]["layouts"][0]["instances"][0]
    tree["x"], tree["y"] = 20.5, 20.0
    err = problems_of(raw)
    assert "structural.layouts[0].instances[0]" in dict(err.problems)
    assert "inside this juniper" in str(err)


def test_start_near_obstacle_inside_safety_radius_is_fine():
    raw = exp1()
    tree = raw["structural"]["layouts"][0]["instances"][0]
    tree["x"], tree["y"] = 20.5, 20.0
    validate_scenario(raw)  # removed by the worker, so not an error


def test_too_many_obstacles():
    raw = exp1()
    inst = raw["structural"]["layouts"][1]["instances"][0]
    raw["structural"]["layouts"][1]["instances"] = [dict(inst) for _ in range(600)]
    assert "at most 512" in str(problems_of(raw))


def test_every_problem_reported_at_once():
    raw = exp1()
    raw["operational"]["start_x"] = float("nan")
    raw["structural"]["layouts"][0]["mesh_name"] = "oak"
    assert len(problems_of(raw).problems) >= 2


def test_file_errors_are_clear(tmp_path):
    with pytest.raises(ScenarioError, match="cannot read"):
        load_scenario(str(tmp_path / "missing.yaml"))
    bad = tmp_path / "bad.yaml"
    bad.write_text("structural: [unclosed\n")
    with pytest.raises(ScenarioError, match="not valid YAML at line"):
        load_scenario(str(bad))
    bad.write_text("- just\n- a list\n")
    with pytest.raises(ScenarioError, match="must be a mapping"):
        load_scenario(str(bad))


def test_docs_list_every_field():
    from asg_scenario.schema import SECTIONS

    doc = open(os.path.join(REPO, "docs", "scenario-format.md")).read()
    for path, fields in SECTIONS:
        for f in fields:
            assert f"| `{f.key}` |" in doc, f"{path}.{f.key} is not documented"


def test_a_request_stored_before_a_field_existed_converts_with_its_default():
    # Issue #27 added textural.fog_visibility_m and cloud_cover; requests stored before (campaign
    # rows, tests/reference) lack them and mean the defaults (no fog, clear sky).
    from asg_scenario.convert import to_scene_msg

    s = load_scenario(os.path.join(REPO, "scenarios", "exp1.yaml"))
    old = dict(s, textural={k: v for k, v in s["textural"].items() if k not in ("fog_visibility_m", "cloud_cover")})
    msg = to_scene_msg(old)
    assert (msg.textural.fog_visibility_m, msg.textural.cloud_cover) == (0.0, 0.0)
    assert msg.textural.sun_yaw_deg == s["textural"]["sun_yaw_deg"]
    with pytest.raises(KeyError):
        to_scene_msg(dict(s, textural={"sun_yaw_deg": 0.0}))  # a required field still is
