"""Rules of the layout a test can hold (issues #38, #56).

asg_agent is built in floors, each importing only from the floors below it (imports inside
functions included): scoring < records < search < campaign < ros < cli; asg_agent/__init__.py and
asg_agent/paths.py are the ground and import nothing of the package. asg_analysis reads what
asg_agent writes and asg_agent never imports it. The planner under test depends on no simulator.
No literal finding threshold lives outside the attribution module (scoring/attribution.py)."""

import ast
import io
import os
import re
import tokenize

REPO = os.path.abspath(os.path.join(os.path.dirname(os.path.realpath(__file__)), ".."))
SRC = os.path.join(REPO, "catkin_ws", "src")
FLOORS = ["scoring", "records", "search", "campaign", "ros", "cli"]
GROUND = {"asg_agent", "asg_agent.paths"}


def modules(package):
    root = os.path.join(SRC, package, "src")
    for folder, _, files in os.walk(os.path.join(root, package)):
        for f in files:
            if f.endswith(".py"):
                path = os.path.join(folder, f)
                name = os.path.relpath(path, root)[:-3].replace(os.sep, ".")
                yield (name[: -len(".__init__")] if name.endswith(".__init__") else name), path


def imports(path, name):
    """(line, module) of every import of the file, at any depth (inside functions too)."""
    tree = ast.parse(open(path, encoding="utf-8").read())
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out += [(node.lineno, a.name) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:  # relative
                base = name.split(".")[: -node.level]
                mod = ".".join(base + ([node.module] if node.module else []))
            else:
                mod = node.module or ""
            out.append((node.lineno, mod))
            out += [(node.lineno, f"{mod}.{a.name}") for a in node.names]
    return out


def floor(module):
    parts = module.split(".")
    return FLOORS.index(parts[1]) if len(parts) > 1 and parts[1] in FLOORS else None


def upward_imports(package="asg_agent", extra=()):
    """Imports from a floor to a higher one, from the ground to any floor, or to asg_analysis."""
    found = []
    for name, path in list(modules(package)) + list(extra):
        here, seen = floor(name), set()
        for line, mod in imports(path, name):
            if line in seen:
                continue
            where = f"{os.path.relpath(path, REPO)}:{line}: {mod}"
            if mod.split(".")[0] == "asg_analysis":
                found.append(where + " (asg_agent never imports the analysis package)")
                seen.add(line)
            elif mod.startswith("asg_agent.") and floor(mod) is not None:
                if name in GROUND or (here is not None and floor(mod) > here):
                    found.append(where)
                    seen.add(line)
    return found


def test_asg_agent_imports_only_downwards_and_never_the_analysis_package():
    assert not upward_imports(), "upward imports:\n  " + "\n  ".join(upward_imports())


def test_the_floor_check_sees_an_upward_import_inside_a_function(tmp_path):
    # the rule itself, on a stand-in module of the search floor reaching up to the campaign's
    # experiment inside a function (issue #56's example) and to asg_analysis at its top
    bad = tmp_path / "methods.py"
    bad.write_text("import asg_analysis.stats\n\ndef f():\n    from asg_agent.campaign.loop import Campaign\n")
    found = upward_imports(package="asg_agent", extra=[("asg_agent.search.methods_standin", str(bad))])
    found = [f for f in found if "methods.py" in f]
    assert len(found) == 2 and any("asg_analysis" in f for f in found) and any(":4:" in f for f in found)


def test_no_import_cycle():
    mods = dict(modules("asg_agent"))
    graph = {m: {d for _, d in imports(p, m) if d in mods and d != m} for m, p in mods.items()}
    # packages' __init__ only re-export; an edge to a package is not a dependency on its modules
    graph = {m: {d for d in ds if not os.path.basename(mods[d]) == "__init__.py"} for m, ds in graph.items()}
    state, stack, cycles = {}, [], []

    def visit(m):
        state[m] = 1
        stack.append(m)
        for d in sorted(graph[m]):
            if state.get(d) == 1:
                cycles.append(stack[stack.index(d) :] + [d])
            elif d not in state:
                visit(d)
        stack.pop()
        state[m] = 2

    for m in sorted(graph):
        if m not in state:
            visit(m)
    assert not cycles, "import cycles: " + "; ".join(" -> ".join(c) for c in cycles)


def test_no_literal_finding_threshold_outside_the_attribution_module():
    found = []
    for name, path in list(modules("asg_agent")) + list(modules("asg_analysis")):
        if name == "asg_agent.scoring.attribution":
            continue
        toks = [
            t
            for t in tokenize.generate_tokens(io.StringIO(open(path, encoding="utf-8").read()).readline)
            if t.type not in (tokenize.COMMENT, tokenize.NL, tokenize.NEWLINE, tokenize.INDENT, tokenize.DEDENT)
        ]
        for a, b in zip(toks, toks[1:]):
            pair = (a.string, b.string)
            if (a.type == tokenize.OP and a.string in (">=", "<", ">", "<=") and b.type == tokenize.NUMBER) or (
                b.type == tokenize.OP and b.string in (">=", "<", ">", "<=") and a.type == tokenize.NUMBER
            ):
                number = b.string if b.type == tokenize.NUMBER else a.string
                if float(number) in (3.0, 4.0):  # (2 is everywhere as "at least two points")
                    found.append(f"{os.path.relpath(path, REPO)}:{a.start[0]}: {' '.join(pair)}")
    assert not found, "literal thresholds (use scoring/attribution.py's constants): " + "; ".join(found)


def test_analysis_reads_stores_and_exports_without_ros():
    # asg_analysis recomputes tables and figures from stores and exports; bags and replays are
    # asg_agent.ros's.
    found = []
    for name, path in modules("asg_analysis"):
        for line, mod in imports(path, name):
            if mod.split(".")[0] in ("rospy", "rosbag", "rosgraph") or mod.startswith("asg_agent.ros"):
                found.append(f"{name}:{line}: {mod}")
    assert not found, "ROS in asg_analysis: " + "; ".join(found)


def test_the_planner_depends_on_no_simulator():
    xml = open(os.path.join(SRC, "asg_planner", "package.xml"), encoding="utf-8").read()
    cmake = open(os.path.join(SRC, "asg_planner", "CMakeLists.txt"), encoding="utf-8").read()
    assert not re.search(r"<(build_|exec_|test_)?depend>asg_sim</", xml), "asg_planner's package.xml names asg_sim"
    assert "asg_sim" not in cmake, "asg_planner's CMakeLists.txt names asg_sim"
