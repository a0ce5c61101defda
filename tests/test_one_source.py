"""Issue #69 item 1: each fact written once across C++ and Python, the other side generated from
it or checked against it here.

- scene defaults: asg_sim's scene.hpp takes every default the schema gives from the generated
  scene_schema.hpp (asg_scenario/cpp_schema.py; test_scenario_schema.py checks the header is
  current), never a literal of its own;
- the vehicle's half width and the traversable height: catalogue.py's, through the same header;
- the registration's worker keys: the scene worker's table (`scene_worker --params`, the rows a
  registration may set) and records/stacks.py's WORKER_KEYS name the same parameters.
"""

import os
import re
import subprocess
import sys

REPO = os.path.abspath(os.path.join(os.path.dirname(os.path.realpath(__file__)), ".."))
sys.path.insert(0, os.path.join(REPO, "catkin_ws", "src", "asg_scenario", "src"))
sys.path.insert(0, os.path.join(REPO, "catkin_ws", "src", "asg_agent", "src"))

from asg_scenario import cpp_schema, schema  # noqa: E402

SIM = os.path.join(REPO, "catkin_ws", "src", "asg_sim")
#: scene.hpp's structs and the schema sections they mirror
STRUCTS = {
    "ObstacleInstance": "structural.layouts[i].instances[j]",
    "Landscape": "structural.landscape",
    "Textural": "textural",
    "Operational": "operational",
}


def struct_members(text: str, struct: str) -> dict:
    """{member: initializer} of `struct NAME { ... };` in C++ source text."""
    body = re.search(rf"struct {struct} \{{(.*?)\n\}};", text, re.S).group(1)
    out = {}
    for decl in re.findall(r"^\s*(?:double|bool|uint32_t)\s+([^;]+);", body, re.M):
        for part in decl.split(","):
            name, _, init = part.partition("=")
            out[name.strip()] = init.strip()
    return out


def test_scene_defaults_come_from_the_generated_schema():
    text = open(os.path.join(SIM, "include", "asg_sim", "scene.hpp"), encoding="utf-8").read()
    sections = dict(schema.SECTIONS)
    checked = 0
    for struct, section in STRUCTS.items():
        members = struct_members(text, struct)
        for f in sections[section]:
            if f.key not in members or f.default is None:
                continue  # required fields: the reader sets them
            want = "schema::" + cpp_schema.constant_name(section, f.key) + ".default_value"
            assert want in members[f.key], f"scene.hpp {struct}.{f.key} = {members[f.key]!r}: use {want}"
            checked += 1
    assert checked >= 18


def test_the_vehicle_and_traversable_height_are_the_catalogues():
    from asg_scenario import catalogue

    header = open(os.path.join(SIM, "include", "asg_sim", "scene_schema.hpp"), encoding="utf-8").read()
    assert f"kVehicleHalfWidth = {catalogue.VEHICLE_HALF_WIDTH!r};" in header
    assert f"kTraversableHeight = {catalogue.TRAVERSABLE_HEIGHT!r};" in header
    for root, _, files in os.walk(os.path.join(SIM, "src")):
        for name in files:
            src = open(os.path.join(root, name), encoding="utf-8").read()
            assert not re.search(r"k(VehicleHalfWidth|TraversableHeight)\s*=", src), f"{name} defines its own"


def test_the_registrations_worker_keys_are_the_scene_workers():
    from asg_agent.records import stacks

    binary = os.path.join(REPO, "catkin_ws", "devel", "lib", "asg_sim", "scene_worker")
    assert os.access(binary, os.X_OK), f"{binary}: not built"
    table = subprocess.run([binary, "--params"], capture_output=True, text=True, check=True).stdout
    rows = [[c.strip() for c in line.strip("|").split("|")] for line in table.splitlines()[2:]]
    settable = {r[0].strip("`") for r in rows if r[4] == "yes"}
    assert settable == set(stacks.WORKER_KEYS), (sorted(settable), sorted(stacks.WORKER_KEYS))
