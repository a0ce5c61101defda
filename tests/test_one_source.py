"""Issue #69 item 1: each fact written once across C++ and Python, the other side generated from
it or checked against it here.

- scene defaults: asg_sim's scene.hpp takes every default the schema gives from the generated
  scene_schema.hpp (asg_scenario/cpp_schema.py; test_scenario_schema.py checks the header is
  current), never a literal of its own;
- the vehicle's half width and the traversable height: catalogue.py's, through the same header;
- the registration's worker keys: the scene worker's table (`scene_worker --params`, the rows a
  registration may set) and records/stacks.py's WORKER_KEYS name the same parameters;
- the scenario file's keys, required fields and integer bounds: the C++ loader (scene_yaml.cpp)
  reads every field through its generated constant and every mapping's keys from the generated
  key lists, with no key list or bound of its own;
- the obstacle catalogue: catalogue.py's entries are generated into the header, and a new class
  is a catalogue entry plus its mesh function (shown below by compiling the meshes with a made-up
  class).
"""

import os
import re
import shutil
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
    # TerrainSpec (terrain.hpp) too (issue #80: its defaults were literals, and the loader keeps a
    # struct's default when the key is missing)
    texts = {
        h: open(os.path.join(SIM, "include", "asg_sim", h), encoding="utf-8").read()
        for h in ("scene.hpp", "terrain.hpp")
    }
    sections = dict(schema.SECTIONS)
    checked = 0
    for struct, section in list(STRUCTS.items()) + [("TerrainSpec", "structural.terrain")]:
        members = struct_members(texts["terrain.hpp" if struct == "TerrainSpec" else "scene.hpp"], struct)
        if struct == "TerrainSpec":
            assert {"amplitude_m", "wavelength_m", "seed"} <= set(members), members
        for f in sections[section]:
            if f.key not in members or f.default is None:
                continue  # required fields: the reader sets them
            want = "schema::" + cpp_schema.constant_name(section, f.key) + ".default_value"
            assert want in members[f.key], f"scene.hpp {struct}.{f.key} = {members[f.key]!r}: use {want}"
            checked += 1
    assert checked >= 21


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


def test_the_cpp_loader_reads_every_field_and_key_list_from_the_generated_header():
    text = open(os.path.join(SIM, "src", "core", "scene_yaml.cpp"), encoding="utf-8").read()
    for name, key, f in cpp_schema.field_rows():
        assert re.search(rf"\bsc::{name}\b", text), f"scene_yaml.cpp does not read {key} through schema::{name}"
        short = key.split(".")[-1]
        assert f'"{short}"' not in text, f"scene_yaml.cpp spells the key {short!r} itself"
    for path, name in cpp_schema.KEY_LISTS.items():
        assert f"sc::kKeys{name}" in text, f"scene_yaml.cpp does not check the keys of {path or 'the file'}"
    # no integer bound or required flag of its own: every reader takes a schema::Field
    assert not re.search(r"\br\.(number|integer|boolean)\([^;]*\b(true|false)\b", text)
    assert not re.search(r"4294967295|4096", text)


def test_python_and_the_header_agree_on_the_key_lists():
    header = open(os.path.join(SIM, "include", "asg_sim", "scene_schema.hpp"), encoding="utf-8").read()
    for path, name in cpp_schema.KEY_LISTS.items():
        listed = re.search(rf"kKeys{name}\[\] = \{{(.*?)\}};", header).group(1)
        assert re.findall(r'"([^"]+)"', listed) == schema.allowed_keys(path), path
    # the Python validator refuses a key outside the same list, at every level
    base = schema.load_scenario(os.path.join(REPO, "scenarios", "exp1.yaml"))
    for path, extra in [("", "weather"), ("operational", "max_speed"), ("structural", "roads")]:
        data = {k: (dict(v) if isinstance(v, dict) else v) for k, v in base.items()}
        (data[path] if path else data)[extra] = 1
        try:
            schema.validate_scenario(data)
        except schema.ScenarioError as e:
            assert any(p.endswith(extra) and "unknown field" in m for p, m in e.problems), e.problems
        else:
            raise AssertionError(f"{path}.{extra} was accepted")


CAIRN_MESH = """
Mesh makeCairn() {  // a made-up class for test_one_source.py: one lathe of stones
  Mesh m;
  addLathe(&m, 6, 8, 0.0f, 0.9f, [](float z, float) { return 0.7f * (1.0f - z); },
           [](int, int) { return V3{0.5f, 0.5f, 0.5f}; });
  return m;
}
"""


def test_a_new_obstacle_class_is_a_catalogue_entry_and_its_mesh_function(tmp_path, monkeypatch):
    """Adds a made-up class "cairn" the way the pages say: one catalogue.py entry and one mesh
    function with its row in meshes.cpp. The generated header then carries it, the C++ catalogue
    and mesh builder know it, and the Python validator accepts a scene with it; nothing else is
    edited."""
    from asg_scenario import catalogue

    monkeypatch.setitem(
        catalogue.MESHES,
        "cairn",
        catalogue.MeshInfo("cairn", 0.9, 0.7, 1.0, "Cairn: a made-up pile of stones", (0.5, 0.5, 0.5)),
    )
    inc = tmp_path / "include" / "asg_sim"
    shutil.copytree(os.path.join(SIM, "include", "asg_sim"), inc)
    (inc / "scene_schema.hpp").write_text(cpp_schema.header_text(), encoding="utf-8")
    src = open(os.path.join(SIM, "src", "core", "meshes.cpp"), encoding="utf-8").read()
    anchor = "struct MeshBuilder {"
    assert anchor in src and '    {"barberry", makeBarberry},\n' in src
    src = src.replace(anchor, CAIRN_MESH + anchor).replace(
        '    {"barberry", makeBarberry},\n', '    {"barberry", makeBarberry},\n    {"cairn", makeCairn},\n'
    )
    (tmp_path / "meshes.cpp").write_text(src, encoding="utf-8")
    (tmp_path / "main.cpp").write_text(
        """#include <cstdio>
#include "asg_sim/meshes.hpp"
int main() {
  for (const auto& m : asg_sim::meshCatalogue())
    std::printf("%s %.2f %.2f %.2f %zu\\n", m.name.c_str(), m.height, m.collision_radius, m.shadow_opacity,
                asg_sim::makeObstacleMesh(m.name).vertices.size());
}
""",
        encoding="utf-8",
    )
    exe = tmp_path / "catalogue"
    subprocess.run(
        [
            "g++",
            "-std=c++17",
            "-O0",
            f"-I{tmp_path / 'include'}",
            "-I/usr/include/eigen3",
            "-o",
            str(exe),
            str(tmp_path / "meshes.cpp"),
            os.path.join(SIM, "src", "core", "terrain.cpp"),
            str(tmp_path / "main.cpp"),
        ],
        check=True,
    )
    rows = [
        line.split()
        for line in subprocess.run([str(exe)], capture_output=True, text=True, check=True).stdout.splitlines()
    ]
    assert [r[0] for r in rows] == sorted(catalogue.MESHES)
    cairn = next(r for r in rows if r[0] == "cairn")
    assert cairn[1:4] == ["0.90", "0.70", "1.00"] and int(cairn[4]) > 0
    scene = schema.load_scenario(os.path.join(REPO, "scenarios", "exp1.yaml"))
    scene["structural"]["layouts"][0]["mesh_name"] = "cairn"
    schema.validate_scenario(scene)
