"""Issue #56: every node's parameters come from its table. Python (asg_lockstep.params): the
segmenter (asg_perception.node_params), the depth stack (asg_depth_stack.params) and the lockstep
client (asg_lockstep.params.CLIENT, which the C++ client reads through a generated header). C++ (asg_lockstep's
table helper, param_table.hpp, which every C++ node uses): the scene worker, wall_clock and the
example twist_driver (`--params`); gap_nav's gap_drive, a user's rospy node with a table of its own
(`--params`). docs/ quotes each table's Markdown; a bad value is
refused naming the parameter and what is allowed; the YAML and launch files hold the tables'
defaults. (The planner's C++ table: tests/test_planner_parameters.py.)"""

import os
import re
import subprocess

import pytest
import yaml

from asg_depth_stack.params import DEPTH_STACK
from asg_lockstep.params import CLIENT, SCRIPTED_DRIVER, Param, markdown, read
from asg_perception.node_params import SEGMENTER

REPO = os.path.abspath(os.path.join(os.path.dirname(os.path.realpath(__file__)), ".."))
TABLES = {
    ("perception.md", "segmenter"): SEGMENTER,
    ("your-stack.md", "depth_stack"): DEPTH_STACK,
    ("your-stack.md", "lockstep_client"): CLIENT,
    ("simulator.md", "scripted_driver"): SCRIPTED_DRIVER,
}


def quoted(doc, name):
    text = open(os.path.join(REPO, "docs", doc), encoding="utf-8").read()
    m = re.search(rf"<!-- params:{name}:begin[^>]*-->\n(.*?)\n<!-- params:{name}:end -->", text, re.S)
    assert m, f"docs/{doc} has no params:{name} block"
    return m.group(1)


@pytest.mark.parametrize("doc,name", list(TABLES))
def test_the_docs_quote_each_table(doc, name):
    assert quoted(doc, name) == markdown(TABLES[(doc, name)]), f"docs/{doc}: regenerate the {name} table"


def test_every_table_reads_its_defaults_and_units_are_written():
    for table in TABLES.values():
        values = read(table, lambda n, d: d)
        assert values == {p.name: p.default for p in table}
        assert all(p.unit and p.doc for p in table)


def test_bad_values_are_refused_by_name():
    def with_(table, **bad):
        return lambda n, d: bad.get(n.replace("/", "__"), d)

    with pytest.raises(ValueError, match=r"~threads = 0: must be an integer in \[1, 64\]"):
        read(SEGMENTER, with_(SEGMENTER, threads=0))
    with pytest.raises(ValueError, match=r"~width = 100: .*a multiple of 32"):
        read(SEGMENTER, with_(SEGMENTER, width=100))
    with pytest.raises(ValueError, match=r"~backend = 'fp64': must be empty or 'eager'"):
        read(SEGMENTER, with_(SEGMENTER, backend="fp64"))
    with pytest.raises(ValueError, match=r"~arcs/arcs = 20: .*odd"):
        read(DEPTH_STACK, with_(DEPTH_STACK, arcs__arcs=20))
    with pytest.raises(ValueError, match=r"~grid/cell = 'half': must be a number"):
        read(DEPTH_STACK, with_(DEPTH_STACK, grid__cell="half"))
    # every bad one at once, each named
    with pytest.raises(ValueError) as e:
        read(DEPTH_STACK, with_(DEPTH_STACK, use_lockstep_client="yes", grid__min_points=1.5, arcs__speed=float("nan")))
    assert all(k in str(e.value) for k in ("~use_lockstep_client", "~grid/min_points", "~arcs/speed"))
    # an integer where a real is asked is taken; a bool where a number is asked is not
    assert read([Param("x", float, 1.0, "m", "x")], lambda n, d: 2)["x"] == 2.0
    with pytest.raises(ValueError):
        read([Param("x", float, 1.0, "m", "x")], lambda n, d: True)


def test_the_depth_stacks_yaml_holds_the_tables_defaults():
    path = os.path.join(REPO, "catkin_ws", "src", "asg_depth_stack", "config", "depth_stack.yaml")
    with open(path, encoding="utf-8") as f:
        data = yaml.safe_load(f)

    def flat(d, prefix=""):
        for k, v in d.items():
            if isinstance(v, dict):
                yield from flat(v, f"{prefix}{k}/")
            else:
                yield f"{prefix}{k}", v

    got = dict(flat(data))
    lockstep = got.pop("lockstep")  # the lockstep client's (CLIENT)
    assert lockstep == CLIENT[0].default
    assert got == {p.name: p.default for p in DEPTH_STACK}


WORKER = os.path.join(REPO, "catkin_ws", "devel", "lib", "asg_sim", "scene_worker")


def worker_table():
    assert os.access(WORKER, os.X_OK), f"{WORKER}: not built"
    return subprocess.run([WORKER, "--params"], capture_output=True, text=True, check=True).stdout


def test_the_scene_workers_table_is_quoted_and_its_yaml_states_its_defaults():
    # The C++ table (asg_sim/src/ros/worker_parameters.hpp): docs/simulator.md quotes its output,
    # and scene_worker.yaml gives each of its keys (stack_nodes, which the node requires, too).
    table = worker_table()
    assert quoted("simulator.md", "scene_worker") == table.rstrip("\n"), "docs/simulator.md: regenerate it"
    rows = [line.split(" | ") for line in table.splitlines()[2:]]
    keys = [r[0].strip("| `") for r in rows]
    path = os.path.join(REPO, "catkin_ws", "src", "asg_sim", "config", "scene_worker.yaml")
    with open(path, encoding="utf-8") as f:
        data = yaml.safe_load(f)
    flat = {
        f"{k}/{kk}" if isinstance(v, dict) else k: vv if isinstance(v, dict) else v
        for k, v in data.items()
        for kk, vv in (v.items() if isinstance(v, dict) else [(None, v)])
    }
    assert set(flat) <= set(keys), f"scene_worker.yaml has keys the table lacks: {set(flat) - set(keys)}"
    for key, row in zip(keys, rows):
        if key == "labels_node":  # empty by default: the YAML leaves it out
            continue
        assert key in flat, f"scene_worker.yaml does not state {key}"
        want = "required" if key == "stack_nodes" else yaml.safe_load(row[2].strip("`"))
        assert want == "required" or flat[key] == want, (key, flat[key], want)
    assert all(r[1].strip() for r in rows), "every row writes its unit"


def test_the_wall_clocks_table_is_quoted_and_its_launch_file_states_its_default():
    # The C++ table of asg_sim/src/ros/wall_clock_node.cpp: docs/your-stack.md quotes its output,
    # and sim_time.launch's `rate` argument defaults to the table's default.
    binary = os.path.join(REPO, "catkin_ws", "devel", "lib", "asg_sim", "wall_clock")
    assert os.access(binary, os.X_OK), f"{binary}: not built"
    table = subprocess.run([binary, "--params"], capture_output=True, text=True, check=True).stdout
    assert quoted("your-stack.md", "wall_clock") == table.rstrip("\n"), "docs/your-stack.md: regenerate it"
    default = float(re.search(r"^\| `rate` \| [^|]+ \| ([0-9.]+) \|", table, re.M).group(1))
    launch = os.path.join(REPO, "catkin_ws", "src", "asg_bringup", "launch", "sim_time.launch")
    arg = re.search(r'<arg name="rate" default="([0-9.]+)"', open(launch, encoding="utf-8").read())
    assert arg and float(arg.group(1)) == default, "sim_time.launch's rate default differs from the table's"


def test_the_cpp_clients_header_is_generated_from_the_same_table():
    # Both lockstep clients read params.CLIENT: the C++ one through a generated header, which
    # must be what the generator writes now (regenerate: python3 -m asg_lockstep.cpp_params).
    from asg_lockstep import cpp_params

    with open(os.path.join(REPO, cpp_params.HEADER), encoding="utf-8") as f:
        assert f.read() == cpp_params.header_text(), f"{cpp_params.HEADER} is stale: regenerate it"
    assert '"lockstep", true, "-", "true or false",' in cpp_params.header_text()


def test_the_twist_drivers_table_is_quoted():
    # The installed C++ example reads its three parameters through the same helper.
    binary = os.path.join(REPO, "catkin_ws", "devel", "lib", "asg_lockstep", "twist_driver")
    assert os.access(binary, os.X_OK), f"{binary}: not built"
    table = subprocess.run([binary, "--params"], capture_output=True, text=True, check=True).stdout
    assert quoted("your-stack.md", "twist_driver") == table.rstrip("\n"), "docs/your-stack.md: regenerate it"
    assert [line.split("|")[1].strip().strip("`") for line in table.splitlines()[2:]] == [
        "speed",
        "gain",
        "max_yaw_rate",
    ]


def test_gap_drives_table_is_printed_quoted_and_its_yaml_holds_its_defaults():
    node = os.path.join(REPO, "catkin_ws", "src", "gap_nav", "nodes", "gap_drive")
    table = subprocess.run(["/usr/bin/python3", node, "--params"], capture_output=True, text=True, check=True).stdout
    assert quoted("your-stack.md", "gap_drive") == table.rstrip("\n"), "docs/your-stack.md: regenerate it"
    rows = {r[1].strip().strip("`"): float(r[3]) for r in (line.split("|") for line in table.splitlines()[2:])}
    path = os.path.join(REPO, "catkin_ws", "src", "gap_nav", "config", "gap_drive.yaml")
    with open(path, encoding="utf-8") as f:
        assert yaml.safe_load(f) == rows


def test_the_scripted_driver_reads_its_table_and_refuses_a_boolean_throttle():
    """Issue #80: scripted_driver read its parameters by hand, so `~throttle: true` drove at
    float(True) = 1.0. It reads SCRIPTED_DRIVER now, which names the bad value."""
    with pytest.raises(ValueError, match=r"~throttle = True: must be a number in \[0, 1\]"):
        read(SCRIPTED_DRIVER, lambda n, d: True if n == "throttle" else d)
    with pytest.raises(ValueError, match="~mode = 'drive'"):
        read(SCRIPTED_DRIVER, lambda n, d: "drive" if n == "mode" else d)
    got = read(SCRIPTED_DRIVER, lambda n, d: {"mode": "goal", "steering": -0.5}.get(n, d))
    assert got == {"mode": "goal", "throttle": 0.5, "steering": -0.5, "brake": 0.0, "ack_name": ""}
    script = open(
        os.path.join(REPO, "catkin_ws", "src", "asg_sim", "scripts", "scripted_driver"), encoding="utf-8"
    ).read()
    assert "read(SCRIPTED_DRIVER" in script and "float(rospy.get_param" not in script


def test_a_registration_mode_other_than_lockstep_or_free_is_refused_by_name():
    """Issue #80: the clients read `stack/mode` as "lockstep or anything else": a typo ran free,
    and in C++ a value of another type read as unset and ran in lockstep. Both now refuse it with
    the same words (asg_lockstep.params.registered_lockstep, client_settings.hpp's gtest)."""
    from asg_lockstep.params import registered_lockstep

    assert (registered_lockstep(None), registered_lockstep("lockstep"), registered_lockstep("free")) == (
        None,
        True,
        False,
    )
    for bad, shown in (("lock-step", "'lock-step'"), (1, "1"), (True, "true")):
        with pytest.raises(ValueError, match=re.escape(f"stack/mode = {shown}: must be 'lockstep' or 'free'")):
            registered_lockstep(bad)
    client = open(
        os.path.join(REPO, "catkin_ws", "src", "asg_lockstep", "src", "asg_lockstep", "ros", "client.py")
    ).read()
    assert 'registered_lockstep(rospy.get_param("stack/mode", None))' in client
