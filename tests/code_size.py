"""Function and test-file sizes of the project's sources (issue #56), for tests/test_code_size.py:
Python functions by their syntax tree, C++ function bodies by brace matching over the source with
comments and literals blanked out (a body is a `{` that follows a parameter list and is not a
control statement's or a lambda's)."""

import ast
import os
import re

CONTROL = {"if", "for", "while", "switch", "catch", "return", "sizeof", "do", "else"}


def python_functions(path):
    """(lines, first line, name) of every function of a Python file, nested ones included."""
    tree = ast.parse(open(path, encoding="utf-8").read())
    return [
        (n.end_lineno - n.lineno + 1, n.lineno, n.name)
        for n in ast.walk(tree)
        if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef))
    ]


def blank_cpp(src):
    """The source with comments and string and character literals removed, newlines kept."""
    out, i, n = [], 0, len(src)
    while i < n:
        if src.startswith("//", i):
            j = src.find("\n", i)
            i = n if j < 0 else j
        elif src.startswith("/*", i):
            j = src.find("*/", i + 2)
            j = n if j < 0 else j + 2
            out.append("\n" * src.count("\n", i, j))
            i = j
        elif src[i] in "\"'":
            quote, j = src[i], i + 1
            while j < n and src[j] != quote:
                j += 2 if src[j] == "\\" else 1
            out.append(quote * 2 + "\n" * src.count("\n", i, j))
            i = j + 1
        else:
            out.append(src[i])
            i += 1
    return "".join(out)


def _opens_function(head):
    h = re.sub(r"\s+", " ", head).strip()
    if not h or h.startswith("#") or re.search(r"=\s*\[|\]\s*\(", h):  # lambdas
        return None
    if re.search(r"\)\s*:\s*[\w:]+\s*[({]", h):  # a constructor's initialiser list
        m = re.search(r"([\w:~]+)\s*\(", h)
        return m.group(1) if m else None
    core = re.sub(r"\)\s*((const|override|noexcept|final|mutable)\s*)*(->\s*[\w:<>,\s*&]+)?$", ")", h)
    m = re.search(r"([\w:~]+)\s*\(", core)
    if core.endswith(")") and m and m.group(1).split("::")[-1] not in CONTROL:
        return m.group(1)
    return None


def cpp_functions(path):
    """(lines, first line, name) of every outermost function body of a C++ file."""
    s = blank_cpp(open(path, encoding="utf-8", errors="replace").read())
    found, stack = [], []
    for i, c in enumerate(s):
        if c == "{":
            head = s[max(0, i - 400) : i]
            k = max(head.rfind(";"), head.rfind("}"), head.rfind("{"))
            stack.append((i, _opens_function(head[k + 1 :])))
        elif c == "}" and stack:
            j, name = stack.pop()
            if name and not any(n for _, n in stack):
                first, last = s.count("\n", 0, j) + 1, s.count("\n", 0, i) + 1
                found.append((last - first + 1, first, name))
    return found


def sources(root, exts, skip=("build", "devel", "asg_tests")):
    for folder, dirs, files in os.walk(root):
        dirs[:] = [d for d in dirs if d not in skip]
        for f in files:
            if f.endswith(exts):
                yield os.path.join(folder, f)
