"""Issue #56: one scenario schema. asg_scenario/schema.py is the one source of the format's keys,
units, ranges, defaults and terminations; asg_sim's C++ validator reads them from the header
generated from it (scene_schema.hpp), so that a range changed in schema.py changes the check on
both sides. Held here: the committed header is what the generator writes now; every range the C++
validator checks comes from that header (no literal bounds left in validateScene); a changed range
changes the Python check and the generated C++ constant; RunScenario.action's constants, the
report's names and the agent's failure set follow the schema's terminations."""

import dataclasses
import os
import re

import pytest

from asg_scenario import cpp_schema, schema
from asg_scenario.report import TERMINATION_NAMES

REPO = os.path.abspath(os.path.join(os.path.dirname(os.path.realpath(__file__)), ".."))
SCENE_CPP = os.path.join(REPO, "catkin_ws", "src", "asg_sim", "src", "core", "scene.cpp")


def test_the_committed_header_is_what_the_schema_generates():
    with open(os.path.join(REPO, cpp_schema.HEADER), encoding="utf-8") as f:
        committed = f.read()
    assert committed == cpp_schema.header_text(), (
        "scene_schema.hpp is stale: python3 -m asg_scenario.cpp_schema > " + cpp_schema.HEADER
    )


def test_every_range_of_the_cpp_validator_comes_from_the_generated_header():
    src = open(SCENE_CPP, encoding="utf-8").read()
    # validateScene and the checks of each section it calls (scene.cpp, from the first of them)
    body = src[src.index("bool insideLandscape(") : src.index("\nvoid placeObstacles(")]
    assert "void validateScene(" in body
    calls = re.findall(r"p\.range\(([^;]*)\);", body)
    assert calls, "validateScene checks no range?"
    literal = [c for c in calls if "schema::k" not in c]
    assert not literal, f"ranges in validateScene not taken from scene_schema.hpp: {literal}"
    names = {n for n, _, _ in cpp_schema.field_rows()}
    used = set(re.findall(r"schema::(k\w+)", body))
    assert used <= names | {"kMaxObstacles"}
    # every bounded numeric field of the scene (not the file-level ones) is checked in C++
    bounded = {n for n, key, f in cpp_schema.field_rows() if f.lo is not None and f.kind is not bool}
    file_level = {"kTopFormatVersion", "kTopScenarioId", "kTerrainSeed", "kTexturalGroundTextureSeed"}
    assert bounded - file_level <= used, sorted(bounded - file_level - used)


def test_a_changed_range_changes_the_check_on_both_sides(monkeypatch):
    fields = list(schema.OPERATIONAL_FIELDS)
    k = next(i for i, f in enumerate(fields) if f.key == "speed")
    line = next(
        ln for ln in cpp_schema.header_text().splitlines() if ln.startswith("constexpr Field kOperationalSpeed{")
    )
    assert '"operational.speed", 0.1, 30.0, "m/s"' in line
    fields[k] = dataclasses.replace(fields[k], hi=12.0)
    monkeypatch.setattr(schema, "OPERATIONAL_FIELDS", fields)
    monkeypatch.setattr(schema, "SECTIONS", [(p, fields if p == "operational" else fs) for p, fs in schema.SECTIONS])
    # C++: the generated constant validateScene reads
    line = next(
        ln for ln in cpp_schema.header_text().splitlines() if ln.startswith("constexpr Field kOperationalSpeed{")
    )
    assert '"operational.speed", 0.1, 12.0, "m/s"' in line
    # Python: the validator reads the same Field
    scenario = schema.load_scenario(os.path.join(REPO, "scenarios", "exp1.yaml"))
    scenario["operational"]["speed"] = 20.0
    with pytest.raises(schema.ScenarioError, match=r"operational.speed.*\[0.1, 12\]"):
        schema.validate_scenario(scenario)


def test_the_terminations_are_declared_once():
    action = open(os.path.join(REPO, "catkin_ws", "src", "asg_msgs", "action", "RunScenario.action")).read()
    consts = [(n, int(v)) for n, v in re.findall(r"^uint8 ([A-Z_]+)=(\d+)", action, re.M)]
    assert consts == [(n, v) for n, v, _ in schema.TERMINATIONS]
    assert TERMINATION_NAMES == [n for n, _, _ in schema.TERMINATIONS]
    from asg_agent.scoring.attribution import FAILED_TERMINATIONS

    assert set(FAILED_TERMINATIONS) == {n for n, _, _ in schema.TERMINATIONS} - {"SUCCESS", "ERROR"}
    header = cpp_schema.header_text()
    for n, v, _ in schema.TERMINATIONS:
        assert f"k{''.join(w.capitalize() for w in n.split('_'))} = {v}," in header
