#!/usr/bin/python3
"""Count test cases in the JUnit XML files under a folder; print one line per failure with the last
lines of its message, the slowest test files with their time (so that the suite's time stays
visible, issue #56), and the closing 'N passed, N failed, N skipped' line. Exit 1 on any failure or
error, or if nothing ran.

A suite's own errors and failures count too: a Python test whose setUpClass raises is written by
rosunit as <testsuite errors="1" tests="0"> with no test case, and would otherwise vanish."""

import glob
import os
import sys
import xml.etree.ElementTree as ET


def suite_level(path, root, suite):
    """The errors and failures a <testsuite> counts that none of its own test cases carries."""
    cases = suite.findall("testcase")
    carried = {
        "errors": sum(c.find("error") is not None for c in cases),
        "failures": sum(c.find("failure") is not None for c in cases),
    }
    out = []
    for kind in ("errors", "failures"):
        try:
            counted = int(suite.get(kind, "0") or 0)
        except ValueError:
            counted = 1  # a count that is not a number is a broken result, not a pass
        if counted > carried[kind]:
            name = f"{os.path.relpath(path, root)}::{suite.get('name', 'testsuite')}"
            why = f"{counted - carried[kind]} suite-level {kind} outside any test case (e.g. setUpClass raised): see the test's log"
            out.append((name, [why]))
    return out


def file_of(path, root, case):
    """The test file a case belongs to: a pytest case's module (its classname without a test
    class), otherwise the result file (one per gtest binary or rostest)."""
    rel = os.path.relpath(path, root)
    if rel.split(os.sep)[0] == "pytest":
        parts = (case.get("classname") or "").split(".")
        while len(parts) > 1 and parts[-1][:1].isupper():
            parts.pop()
        return f"{os.path.splitext(os.path.basename(path))[0]}: {'.'.join(parts)}"
    return rel


def slowest(times, top=15):
    """Lines for the `top` files that took longest, and the total."""
    lines = [f"slowest test files ({len(times)} files, {sum(times.values()) / 60:.1f} min in all):"]
    for name, t in sorted(times.items(), key=lambda kv: -kv[1])[:top]:
        lines.append(f"  {t:8.1f} s  {name}")
    return lines


def main(root):
    passed, failed, skipped, bad_files = 0, [], 0, []
    times = {}
    for path in sorted(glob.glob(os.path.join(root, "**", "*.xml"), recursive=True)):
        try:
            tree = ET.parse(path)
        except ET.ParseError as e:
            bad_files.append(f"{path}: unreadable result file ({e})")
            continue
        for suite in tree.getroot().iter("testsuite"):
            failed.extend(suite_level(path, root, suite))
        for case in tree.getroot().iter("testcase"):
            try:
                seconds = float(case.get("time", "0") or 0)
            except ValueError:
                seconds = 0.0
            key = file_of(path, root, case)
            base = os.path.basename(path)
            wrapped = base.startswith("rostest-") and os.path.exists(
                os.path.join(os.path.dirname(path), "rosunit-" + base[len("rostest-") :])
            )
            if not wrapped:  # a rostest's own file times the rosunit run it wraps: counted once
                times[key] = times.get(key, 0.0) + seconds
            name = f"{os.path.relpath(path, root)}::{case.get('classname', '')}.{case.get('name')}"
            bad = case.find("failure")
            bad = bad if bad is not None else case.find("error")
            if bad is not None:
                text = (bad.text or bad.get("message") or "").strip().splitlines()
                failed.append((name, text[-3:]))
            elif case.find("skipped") is not None:
                skipped += 1
            else:
                passed += 1
    for name, why in failed:
        print(f"FAILED {name}")
        for line in why:
            print(f"    {line[:300]}")
    for line in bad_files:
        print(f"FAILED {line}")
    total_failed = len(failed) + len(bad_files)
    if times:
        print("\n".join(slowest(times)))
    print(f"tests: {passed} passed, {total_failed} failed, {skipped} skipped")
    return 1 if total_failed or passed == 0 else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1]))
