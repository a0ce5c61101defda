"""Issues #56 and #69: no function in catkin_ws/src over 100 lines, with no exception list, and no
test file over 500 lines. The measures themselves are checked on small sources."""

import os
import re

from code_size import cpp_functions, python_functions, sources

REPO = os.path.abspath(os.path.join(os.path.dirname(os.path.realpath(__file__)), ".."))
SRC = os.path.join(REPO, "catkin_ws", "src")
LIMIT, TEST_LIMIT = 100, 500


def long_functions():
    out = {}
    for path in sources(SRC, (".py",)):
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
