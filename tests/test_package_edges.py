"""Issue #80 item 2: every edge between the project's packages is declared and none runs in a
circle. An edge is what a package's code does with another: imports it (at any depth), or runs
one of its executables (`asg_scenario.binaries.find_binary(PACKAGE, NAME)`, the one way the
project finds another package's executable, as ROS does). Each must be a dependency in the
package's package.xml (code under test/ may use test_depend), and so must each third-party
module it imports (MODULE_KEYS: the rosdep key of each; PyPI wheels are pinned by
scripts/common.sh instead). The declared asg_* dependencies form no circle. A made-up tree shows
the check failing on an undeclared edge."""

import ast
import os
import re
import sys
import xml.etree.ElementTree as ET

REPO = os.path.abspath(os.path.join(os.path.dirname(os.path.realpath(__file__)), ".."))
SRC = os.path.join(REPO, "catkin_ws", "src")
RUN = ("depend", "exec_depend", "build_export_depend")
TEST = RUN + ("test_depend", "build_depend")
#: third-party modules and the rosdep key (Debian's package) a package.xml declares for each
MODULE_KEYS = {
    "numpy": "python3-numpy",
    "yaml": "python3-yaml",
    "torch": "python3-torch",
    "sklearn": "python3-sklearn",
    "scipy": "python3-scipy",
    "cv2": "python3-opencv",
    "matplotlib": "python3-matplotlib",
    "tqdm": "python3-tqdm",
}
#: wheels from PyPI, pinned by scripts/common.sh (no rosdep key)
PIP = {"cma", "ribs", "tensorboardX", "onnxruntime", "openvino", "orjson"}
BINARY = re.compile(r"find_binary\(\s*\"(\w+)\"\s*,\s*\"(\w+)\"")


def packages(src=SRC):
    """{package: {"run": set, "test": set}} of the package.xml files under `src`."""
    out = {}
    for name in sorted(os.listdir(src)):
        xml = os.path.join(src, name, "package.xml")
        if os.path.isfile(xml) and not os.path.islink(os.path.join(src, name)):
            root = ET.parse(xml).getroot()
            dep = {tag: {el.text.strip() for el in root.iter(tag) if el.text} for tag in TEST}
            out[root.findtext("name")] = {
                "run": set().union(*(dep[t] for t in RUN)),
                "test": set().union(*dep.values()),
                "dir": os.path.join(src, name),
            }
    return out


def python_files(folder):
    for root, dirs, files in os.walk(folder):
        dirs[:] = [d for d in dirs if d not in ("build", "devel", "__pycache__")]
        for f in files:
            path = os.path.join(root, f)
            if f.endswith(".py") or ("." not in f and open(path, "rb").readline().startswith(b"#!/usr/bin/env python")):
                yield path
            elif "." not in f and b"python" in open(path, "rb").readline():
                yield path


def edges(src=SRC):
    """[(package, kind, what, where, is_test)]: every import of another package or third-party
    module, and every executable of another package it runs."""
    pkgs = packages(src)
    out = []
    for pkg, info in pkgs.items():
        for path in python_files(info["dir"]):
            rel = os.path.relpath(path, info["dir"])
            is_test = rel.startswith("test") or os.path.basename(path).startswith("test_") or pkg == "asg_tests"
            text = open(path, encoding="utf-8").read()
            for node in ast.walk(ast.parse(text)):
                names = []
                if isinstance(node, ast.Import):
                    names = [a.name for a in node.names]
                elif isinstance(node, ast.ImportFrom) and node.module and not node.level:
                    names = [node.module]
                for n in names:
                    top = n.split(".")[0]
                    if top != pkg and (top in pkgs or top in MODULE_KEYS):
                        out.append((pkg, "imports", top, f"{rel}:{node.lineno}", is_test))
            for m in BINARY.finditer(text):
                if m.group(1) != pkg:
                    out.append((pkg, "runs", m.group(1), f"{rel}: {m.group(2)}", is_test))
    return out


def undeclared(src=SRC):
    pkgs = packages(src)
    bad = []
    for pkg, kind, what, where, is_test in edges(src):
        key = MODULE_KEYS.get(what, what)
        if key not in pkgs[pkg]["test" if is_test else "run"]:
            bad.append(f"{pkg} {kind} {what} ({where}) without declaring {key}")
    return sorted(set(bad))


def circles(src=SRC):
    pkgs = packages(src)
    graph = {p: {d for d in info["run"] if d in pkgs} for p, info in pkgs.items()}
    found = []

    def walk(p, path):
        for d in sorted(graph[p]):
            if d in path:
                found.append(" -> ".join(path[path.index(d) :] + [d]))
            elif len(path) < len(graph):
                walk(d, path + [d])

    for p in sorted(graph):
        walk(p, [p])
    return sorted(set(found))


def test_every_edge_is_declared():
    assert undeclared() == []


def test_no_declared_circle():
    assert circles() == []


def test_the_edges_the_review_found_are_seen_and_declared():
    seen = {(p, k, w) for p, k, w, _, _ in edges()}
    for want in (
        ("asg_agent", "runs", "asg_sim"),  # hardening: asg_sim_dataset
        ("asg_agent", "runs", "asg_planner_harness"),  # baseline offline: asg_closed_loop
        ("asg_agent", "imports", "sklearn"),  # the surrogate
        ("asg_perception", "runs", "asg_sim"),  # spread: asg_sim_dataset
        ("asg_analysis", "runs", "asg_sim"),  # pictures: asg_sim_render
    ):
        assert want in seen, want
    assert not [e for e in seen if e[0] == "asg_scenario" and e[2] == "asg_sim"]  # it ran up before


def test_the_pip_wheels_are_pinned_by_the_setup():
    text = open(os.path.join(REPO, "scripts", "common.sh"), encoding="utf-8").read()
    for wheel in PIP:
        assert re.search(rf"\b{wheel}==[\d.]+", text), wheel


def _pkg(root, name, deps, code):
    d = root / name
    (d / "src" / name).mkdir(parents=True)
    (d / "package.xml").write_text(
        f"<package format='2'><name>{name}</name>" + "".join(f"<depend>{x}</depend>" for x in deps) + "</package>"
    )
    (d / "src" / name / "__init__.py").write_text(code)


def test_the_check_fails_on_an_undeclared_edge_and_a_circle(tmp_path):
    _pkg(tmp_path, "pa", ["pb"], "import pb\n")
    _pkg(tmp_path, "pb", [], 'def f():\n    from pc import x\n    return find_binary("pa", "tool")\nimport numpy\n')
    _pkg(tmp_path, "pc", ["pa"], "")
    bad = undeclared(str(tmp_path))
    assert any(b.startswith("pb imports pc") for b in bad)  # inside a function too
    assert any(b.startswith("pb runs pa") for b in bad)
    assert any("pb imports numpy" in b and "python3-numpy" in b for b in bad)
    assert not [b for b in bad if b.startswith("pa ")]
    (tmp_path / "pb" / "package.xml").write_text(
        "<package format='2'><name>pb</name><depend>pc</depend><exec_depend>pa</exec_depend>"
        "<depend>python3-numpy</depend></package>"
    )
    assert undeclared(str(tmp_path)) == []
    assert circles(str(tmp_path)) and all("pa" in c and "pb" in c for c in circles(str(tmp_path)))


if __name__ == "__main__":
    sys.exit(print("\n".join(undeclared() + circles())))
