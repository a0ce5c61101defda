"""Issue #38: rules of the layout a test can hold. No import cycle among asg_agent's modules
(function-level imports included), and no literal finding threshold outside the attribution
module (scoring/attribution.py: FINDING, FINDING_STRONG, REFERENCE_CLEAR, CANDIDATE)."""

import ast
import io
import os
import tokenize

SRC = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "src"))
PKG = os.path.join(SRC, "asg_agent")


def modules():
    for folder, _, files in os.walk(PKG):
        for f in files:
            if f.endswith(".py"):
                path = os.path.join(folder, f)
                name = os.path.relpath(path, SRC)[:-3].replace(os.sep, ".")
                yield (name[: -len(".__init__")] if name.endswith(".__init__") else name), path


def imports(path, name):
    tree = ast.parse(open(path, encoding="utf-8").read())
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom):
            if node.level:  # relative
                base = name.split(".")[: -node.level]
                mod = ".".join(base + ([node.module] if node.module else []))
            else:
                mod = node.module or ""
            out.add(mod)
            out |= {f"{mod}.{a.name}" for a in node.names}
    return {m for m in out if m.startswith("asg_agent")}


def test_no_import_cycle():
    mods = dict(modules())
    graph = {m: {d for d in imports(p, m) if d in mods and d != m} for m, p in mods.items()}
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
    for name, path in modules():
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
                    found.append(f"{os.path.relpath(path, SRC)}:{a.start[0]}: {' '.join(pair)}")
    assert not found, "literal thresholds (use scoring/attribution.py's constants): " + "; ".join(found)


def test_analysis_reads_stores_and_exports_without_ros():
    # analysis/ recomputes tables and figures from stores and exports; bags and replays are ros/'s.
    found = []
    for name, path in modules():
        if not name.startswith("asg_agent.analysis"):
            continue
        tree = ast.parse(open(path, encoding="utf-8").read())
        for node in ast.walk(tree):
            mods = []
            if isinstance(node, ast.Import):
                mods = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and not node.level:
                mods = [node.module or ""]
            found += [f"{name}:{node.lineno}: {m}" for m in mods if m.split(".")[0] in ("rospy", "rosbag", "rosgraph")]
            found += [f"{name}:{node.lineno}: {m}" for m in mods if m.startswith("asg_agent.ros")]
    assert not found, "ROS in analysis/: " + "; ".join(found)
