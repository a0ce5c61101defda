#!/usr/bin/python3
"""Keep the console of `catkin_make run_tests` to what a reader needs (issue #38): every line goes
to LOG; the console gets one line per finished test file and the lines that report a failure.
The fault-injection tests make nodes log [ERROR] on purpose (a bad goal refused, a stack that
crashes); those stay in LOG, beside everything else, so that the console shows only what failed.
    catkin_make run_tests 2>&1 | console_filter.py LOG"""

import re
import sys

# What the console shows, each with what it is.
SHOWN = [
    re.compile(r"^\[ROSUNIT\] Outputting test results to "),  # a rostest or rosunit file finished
    re.compile(r"^\[ *(PASSED|FAILED) *\]"),  # gtest: a binary's verdict and each failed case
    re.compile(r"^\[Testcase: .*\] \.\.\. (FAILURE|ERROR)"),  # unittest inside a rostest
    re.compile(r"^\S+:\d+(:\d+)?: (fatal )?error: "),  # the compiler
    re.compile(r"^make(\[\d+\])?: \*\*\* "),  # the build stopped
    re.compile(r"^ \* (RESULT|TESTS|ERRORS|FAILURES): "),  # a rostest's own summary
    re.compile(r"^(FAILED|ERROR) \S+::"),  # pytest's short summary of a failed test
]


def shown(line: str) -> bool:
    return any(p.search(line) for p in SHOWN)


def main(log_path: str) -> int:
    with open(log_path, "w", encoding="utf-8", errors="replace") as log:
        for line in sys.stdin:
            log.write(line)
            if shown(line):
                sys.stdout.write(line)
                sys.stdout.flush()
    print(f"(the whole output of the tests, nodes' expected errors included: {log_path})")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1]))
