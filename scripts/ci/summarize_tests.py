#!/usr/bin/python3
"""Count test cases in the JUnit XML files under a folder; print one line per failure with the last
lines of its message, and the closing 'N passed, N failed, N skipped' line. Exit 1 on any failure or error, or if nothing ran."""

import glob
import os
import sys
import xml.etree.ElementTree as ET


def main(root):
    passed, failed, skipped, bad_files = 0, [], 0, []
    for path in sorted(glob.glob(os.path.join(root, "**", "*.xml"), recursive=True)):
        try:
            tree = ET.parse(path)
        except ET.ParseError as e:
            bad_files.append(f"{path}: unreadable result file ({e})")
            continue
        for case in tree.getroot().iter("testcase"):
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
    print(f"tests: {passed} passed, {total_failed} failed, {skipped} skipped")
    return 1 if total_failed or passed == 0 else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1]))
