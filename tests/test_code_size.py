"""Issues #56, #69 and #80: no function over 100 lines anywhere in the repository (Python: every
file by its name or `#!` line, tests/ and scripts/ included; C++: catkin_ws/src), with no exception
list, and no test file over 500 lines. The measures themselves are checked on small sources."""

import os
import re

from code_size import cpp_functions, python_functions, sources

REPO = os.path.abspath(os.path.join(os.path.dirname(os.path.realpath(__file__)), ".."))
SRC = os.path.join(REPO, "catkin_ws", "src")
LIMIT, TEST_LIMIT = 100, 500


#: folders of the repository that hold no source of the project's (build outputs, data, runs)
NOT_SOURCES = {".git", "build", "devel", "install", "results", "runs", "__pycache__", "node_modules"}


def python_sources(root=REPO):
    """Every Python file of the repository (issue #80 item 8: tests/, scripts/ and the nodes
    without `.py`, such as gap_drive and scripted_driver, too): by its name or its `#!` line."""
    for folder, dirs, files in os.walk(root):
        dirs[:] = sorted(d for d in dirs if d not in NOT_SOURCES and not d.startswith("."))
        for f in sorted(files):
            path = os.path.join(folder, f)
            if os.path.islink(path):
                continue
            if f.endswith(".py"):
                yield path
            elif "." not in f:
                with open(path, "rb") as fh:
                    if b"python" in fh.readline():
                        yield path


def long_functions():
    out = {}
    for path in python_sources():
        for n, line, name in python_functions(path):
            if n > LIMIT:
                out[(os.path.relpath(path, REPO), name)] = n
    for path in sources(SRC, (".cpp", ".hpp", ".h")):
        for n, line, name in cpp_functions(path):
            if n > LIMIT:
                out[(os.path.relpath(path, REPO), name)] = n
    return out


def test_no_function_over_100_lines():
    got = long_functions()
    assert not got, "over %d lines: %s" % (
        LIMIT,
        "; ".join(f"{f}:{name} ({n} lines)" for (f, name), n in sorted(got.items())),
    )


def test_no_test_file_over_500_lines():
    big = []
    for root in (SRC, os.path.join(REPO, "tests")):
        for path in sources(root, (".py", ".cpp")):
            name = os.path.basename(path)
            if re.match(r"(test_.*|.*_check)\.(py|cpp)$", name):
                n = sum(1 for _ in open(path, encoding="utf-8"))
                if n > TEST_LIMIT:
                    big.append(f"{os.path.relpath(path, REPO)} ({n} lines)")
    assert not big, "test files over %d lines: %s" % (TEST_LIMIT, ", ".join(big))


def test_the_measures_on_small_sources(tmp_path):
    cpp = tmp_path / "a.cpp"
    cpp.write_text(
        "// f() { not code\nnamespace x {\nint f(int a) const {\n  if (a) {\n    return 1;\n  }\n"
        '  auto g = [](int b) {\n    return b;\n  };\n  const char* s = "}{";\n  return 0;\n}\n'
        "Foo::Foo(int a) : a_(a) {\n}\n}  // namespace x\n"
    )
    assert [(n, first, name) for n, first, name in cpp_functions(str(cpp))] == [(10, 3, "f"), (2, 13, "Foo::Foo")]
    py = tmp_path / "a.py"
    py.write_text("def f():\n    def g():\n        pass\n    return g\n")
    assert sorted(python_functions(str(py))) == [(2, 2, "g"), (4, 1, "f")]


def test_the_whole_tree_is_read():
    # the places the check missed before issue #80: tests/ (through no link), scripts/, and
    # Python nodes without `.py`
    seen = {os.path.relpath(p, REPO) for p in python_sources()}
    for want in (
        "tests/campaign_check.py",
        "scripts/ci/run_parallel.py",
        "catkin_ws/src/gap_nav/nodes/gap_drive",
        "catkin_ws/src/asg_sim/scripts/scripted_driver",
    ):
        assert want in seen, want
    assert not [p for p in seen if p.startswith(("catkin_ws/build", "catkin_ws/devel", "results/"))]
