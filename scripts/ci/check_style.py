#!/usr/bin/python3
"""CI helper (issue #26): the project's Python formatted and linted by ruff (ruff.toml), written
as two JUnit test cases so that scripts/test.sh counts them with the rest.
    check_style.py REPO OUT.xml"""

import subprocess
import sys
from xml.sax.saxutils import escape


def main(repo: str, out: str) -> int:
    cases = []
    for name, args in (
        ("ruff_check", ["check", "--no-cache", "."]),
        ("ruff_format", ["format", "--check", "--no-cache", "."]),
    ):
        try:
            p = subprocess.run([sys.executable, "-m", "ruff"] + args, cwd=repo, capture_output=True, text=True)
            ok, text = p.returncode == 0, (p.stdout + p.stderr).strip()
        except OSError as e:
            ok, text = False, f"cannot run ruff: {e}"
        if not ok:
            print(f"{name}: {text[-3000:]}\n(fix with `ruff format .` and `ruff check --fix .`)", file=sys.stderr)
        body = "" if ok else f'<failure message="ruff {args[0]} failed">{escape(text[-20000:])}</failure>'
        cases.append(f'<testcase classname="style" name="{name}">{body}</testcase>')
    with open(out, "w") as f:
        f.write(f'<testsuite name="style" tests="{len(cases)}">' + "".join(cases) + "</testsuite>\n")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], sys.argv[2]))
