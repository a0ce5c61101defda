#!/usr/bin/python3
"""Count test cases in the JUnit XML files under a folder; print one line per failure with the last
lines of its message, the slowest test files with their time (so that the suite's time stays
visible, issue #56), and the closing 'N passed, N failed, N skipped' line. Exit 1 on any failure or
error, or if nothing ran. Every file's time [s] also goes to FOLDER/times.json, with the CPU's name
and core count, so that two runs on one CPU class can be compared file by file (issue #69):
`summarize_tests.py --compare BEFORE/times.json AFTER/times.json`.

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
    class) after its folder's name, otherwise the result file (one per gtest binary or rostest)."""
    rel = os.path.relpath(path, root).split(os.sep)
    if rel[0] == "pytest" and len(rel) > 1:
        parts = (case.get("classname") or "").split(".")
        while len(parts) > 1 and parts[-1][:1].isupper():
            parts.pop()
        # pytest/PKG.xml, or pytest/PKG/PART.xml for a folder run in parts (run_parallel.py)
        return f"{os.path.splitext(rel[1])[0]}: {'.'.join(parts)}"
    return os.sep.join(rel)


def slowest(times, top=15):
    """Lines for the `top` files that took longest, and the total."""
    lines = [f"slowest test files ({len(times)} files, {sum(times.values()) / 60:.1f} min in all):"]
    for name, t in sorted(times.items(), key=lambda kv: -kv[1])[:top]:
        lines.append(f"  {t:8.1f} s  {name}")
    return lines


def write_times(root, times):
    """FOLDER/times.json: {cpu, cores, files: {test file: seconds}}, and wall_s, the whole run's
    seconds measured from ASG_SUITE_START (scripts/test.sh sets it when it starts; issue #79: a
    suite-time record's wall time is measured, not typed)."""
    import json

    cpu = ""
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as f:
            cpu = next((ln.split(":", 1)[1].strip() for ln in f if ln.startswith("model name")), "")
    except OSError:
        pass
    record = {"cpu": cpu, "cores": os.cpu_count(), "files": {k: round(v, 1) for k, v in sorted(times.items())}}
    start = os.environ.get("ASG_SUITE_START", "")
    if start:
        import time

        try:
            record["wall_s"] = round(time.time() - float(start), 1)
            record["wall_s_from"] = "scripts/test.sh (ASG_SUITE_START to the summary)"
        except ValueError:
            print(f"summarize_tests: ASG_SUITE_START={start!r} is not a time in seconds; no wall_s", file=sys.stderr)
    with open(os.path.join(root, "times.json"), "w", encoding="utf-8") as f:
        json.dump(record, f, indent=1, sort_keys=True)
        f.write("\n")


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
        write_times(root, times)
    print(f"tests: {passed} passed, {total_failed} failed, {skipped} skipped")
    return 1 if total_failed or passed == 0 else 0


def compare(before_path, after_path):
    """Two times.json files, file by file: the files both ran, and those only one of them ran."""
    import json

    before, after = (json.load(open(p, encoding="utf-8")) for p in (before_path, after_path))
    a, b = before["files"], after["files"]
    both = sorted(set(a) & set(b))
    ta, tb = sum(a[k] for k in both), sum(b[k] for k in both)
    print(
        f"before: {before.get('cpu', '?')}, {before.get('cores', '?')} cores; after: {after.get('cpu', '?')}, {after.get('cores', '?')} cores"
    )
    print(f"files in both: {len(both)}, {ta:.1f} s before, {tb:.1f} s after ({tb / ta if ta else float('nan'):.2f}x)")
    only_a, only_b = sorted(set(a) - set(b)), sorted(set(b) - set(a))

    def files(n):
        return f"{n} file" + ("" if n == 1 else "s")

    print(
        f"only before: {files(len(only_a))}, {sum(a[k] for k in only_a):.1f} s; "
        f"only after: {files(len(only_b))}, {sum(b[k] for k in only_b):.1f} s"
    )
    for k in sorted(both, key=lambda k: -abs(b[k] - a[k]))[:15]:
        print(f"  {a[k]:8.1f} s -> {b[k]:8.1f} s  {k}")
    return 0


if __name__ == "__main__":
    if len(sys.argv) == 4 and sys.argv[1] == "--compare":
        sys.exit(compare(sys.argv[2], sys.argv[3]))
    sys.exit(main(sys.argv[1]))
