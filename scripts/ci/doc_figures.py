#!/usr/bin/python3
"""Figures in the docs with no test or generated block beside them (issue #68).

For README.md, every docs/*.md and every study record (docs/studies/*.md) this finds the *figures*, numbers that state a measurement, and
sorts each into one of three kinds: checked by a test, in a generated block, or left. "Left" is
what is still to tie to a test or to a generator. This is a heuristic that reads text. It can
call a figure checked when the test checks something else, and it misses checks that compute a
figure, so read "checked" as "a test quotes it", not as proof.

What counts as a figure, in prose and in table cells (outside code):
  - a decimal (0.48, 157.8), a number with thousands commas (1,477), a number in scientific
    notation (1e-5);
  - a percentage (25.5 %), a ratio (2.3x), a fraction of counts (12/14), "N of M" (47 of its 53);
  - an integer with a unit of measure (15 s, 60 Hz, 10 m, 3 MB) or with a counted outcome
    (57 findings, 300 scenarios, 104 frames);
  - a table cell that is only a number (| 57 |).
Not figures: bare integers in prose (round 3, 2 cores, seed 0), issue numbers (#54), dates,
version numbers (Debian 12, Mesa 22.3, 1.2.3), numbers that name things (Exp. 1, Round 3, step 4,
job 116, Table 2), file names and paths, links, code spans (also over two lines), command-line
options (--seeds 3, seed:=0), list and heading numbering, adjectives (2-core, 8-connected) and
"per 1,000".

What is not read at all: fenced and indented code blocks, HTML comments, this scanner's own block
in docs/testing.md, and parameter tables (first header cell "parameter", "option", "key", "field"
or "argument") that a test checks as a whole: a test file names the page and quotes the heading
line of the table's section (e.g. "## planner node" in tests/test_launch_files.py).

A figure is *in a generated block* when it lies between markers that a generator rewrites:
`<!-- NAME:begin ... -->` ... `<!-- NAME:end -->` (also written `NAME: begin` / `NAME: end`), or
`<!-- NAME -->` ... `<!-- end NAME -->`.

A figure is *checked by a test* when a test file (tests/*.py, catkin_ws/src/*/test/*.py) holds it:
  (a) the file names the page (its file name, e.g. "design-loop.md", as a DOC = ... line does)
      and holds the figure's number as written (1,477 also as 1477), not inside a longer number;
      only numbers with at least 3 significant digits count here (157.8, 1,477, 0.116; not 0.48,
      300 or 4.2, which turn up in any file);
  (b) a file holds a 6-word stretch of the page's text that includes the figure, or a file that
      names the page holds such a 4-word stretch with at least two words of letters;
  (c) a file holds a 6-word stretch of the page's text, at least three of them words, with a
      placeholder ({x:.1f}, %d) where the figure stands: an f-string the test fills from the
      results and looks for in the page.
Stretches are compared word by word, with ** and blockquote marks dropped and quotes, brackets
and punctuation stripped from the ends of words; string literals that end one line of a test and
start the next ("a " then "b") are read as one. A stretch quoted in a comment counts too.
Everything else is *left*.

    python3 scripts/ci/doc_figures.py                    # per page: counts, then every figure left
    python3 scripts/ci/doc_figures.py --markdown         # summary table, up to 10 lines left a page
    python3 scripts/ci/doc_figures.py --json FILE        # every figure with its kind, as JSON
    python3 scripts/ci/doc_figures.py --doc docs/testing.md [--check]   # the block of docs/testing.md
"""

import argparse
import glob
import json
import os
import re
import sys

REPO = os.path.abspath(os.path.join(os.path.dirname(os.path.realpath(__file__)), "..", ".."))
BEGIN, END = "<!-- doc figures: begin -->", "<!-- doc figures: end -->"
COMMAND = "python3 scripts/ci/doc_figures.py --doc docs/testing.md"
WINDOW = 6  # words in a stretch of text that rule (b) looks for in the tests
SHORT = 4  # words in a stretch that rule (b) looks for in the tests that name the page
MIN_DIGITS = 3  # digits a number needs for rule (a)

NUM = r"\d{1,3}(?:,\d{3})+(?:\.\d+)?|\d+(?:\.\d+)?"
FIG = re.compile(rf"(?<![\w.,])(?P<num>{NUM})(?P<tail>\s?%|x\b|×|e-?\d+\b|/(?:{NUM})(?![\w/]))?")
UNITS = (
    r"ms|s|sec|secs|seconds?|min|mins|minutes?|h|hours?|days?|CPU-hours?|core-hours?|Hz|kHz|fps|"
    r"m|cm|mm|km|m/s|rad|rad/s|deg|°|px|MB|GB|KB|kB|MiB|GiB|KiB|bytes?|ms/frame|µs|us|ns"
)
COUNTED = (
    r"findings?|failures?|collisions?|timeouts?|flips?|scenarios?|scenes?|runs?|frames?|layouts?|"
    r"episodes?|pixels?|vertices|samples?|hits?|misses|passes|fails|errors?|tests?|cases?|replays?|"
    r"trials?|campaigns?|kills?|restarts?|re-queues?"
)
UNIT = re.compile(rf"\s?(?:{UNITS})(?![\w/])|\s(?:{COUNTED})\b")
OF = re.compile(rf"\s+(?:out\s+)?of\s+(?:(?:the|its|their|all)\s+)?(?:{NUM})(?![\w.])")
NAMED = (
    r"Exp\.|Exps\.|[Ee]xperiments?|[Rr]ounds?|[Ss]ections?|[Ss]teps?|[Ii]tems?|[Jj]obs?|[Ss]eeds?|"
    r"[Ii]ssues?|[Pp]hases?|[Ll]evels?|[Pp]arts?|[Pp]orts?|[Ll]ines?|[Tt]ables?|Fig\.|[Ff]igures?|"
    r"[Vv]ersions?|format_version|[Cc]ommits?|[Ww]orkers?|[Aa]rms?|Debian|Ubuntu|Mesa|Python|ROS|"
    r"Noetic|OpenCV|OpenGL|torch|PyTorch|CUDA|numpy|gcc|GCC|LLVM|llvm|oneDNN|OpenVINO|ONNX|opset|[Cc]ores?|Debian's"
)
BLANKS = [
    re.compile(r"<!--.*?-->"),  # an HTML comment
    re.compile(r"``.*?``|`[^`]*`"),  # a code span
    re.compile(r"(?<=\])\([^)]*\)"),  # a link's target
    re.compile(r"https?://\S+"),
    re.compile(r"(?<![\w-])--?[A-Za-z][\w-]*(?:[ =](?:\d[\w.,:/-]*))?"),  # an option and its value
    re.compile(r"\w+:=\S*"),  # a roslaunch argument
    re.compile(r"#\d+"),  # an issue
    re.compile(r"\b\d{4}-\d{2}(?:-\d{2})?\b"),  # a date
    re.compile(r"\b\d+(?:\.\d+){2,}\b"),  # a version
    re.compile(rf"(?<![\w.])(?:{NAMED})\s+\d+(?:\.\d+)?(?:\s*(?:-|–|\.\.|,|and|or|to)\s*\d+(?:\.\d+)?)*"),
    re.compile(r"\b(?=[0-9a-f]*[a-f])(?=[0-9a-f]*\d)[0-9a-f]{7,40}\b"),  # a commit
    re.compile(r"\bper\s+1,?000\b"),  # a unit: "per 1,000"
]
PATH = re.compile(r"[\w.~{},*-]*(?:/[\w.~{},*-]+)+/?|[\w.-]*\w\.(?:md|py|yaml|yml|json|jsonl|gz|csv|png|sh)\b")
LIST = re.compile(r"^(\s*(?:#+\s+)?)(\d+(?:\.\d+)*[.)])(?=\s)")  # "1. ", "## 3. ", "2) "
PLACEHOLDER = re.compile(r"\{[^{}\n]*\}|%(?:\(\w+\))?[-+ 0#]*\d*(?:\.\d+)?[sdfgr]")  # {x:.1f}, %d
MASK = "{}"
WHOLE_TABLE = {"parameter", "option", "key", "field", "argument"}


def blank(text, start, end):
    return text[:start] + " " * (end - start) + text[end:]


def prose_of(line):
    """The line with everything that is not prose blanked, columns kept."""
    s = line
    m = LIST.match(s)
    if m:
        s = blank(s, m.start(2), m.end(2))
    for rx in BLANKS:
        s = rx.sub(lambda m: " " * len(m.group()), s)
    return PATH.sub(lambda m: " " * len(m.group()) if is_path(m.group()) else m.group(), s)


def is_path(token):
    """Whether a token with a slash names a file or folder, not a unit (rad/s, ms/frame) nor a
    fraction (12/14)."""
    return bool(re.search(r"[A-Za-z]", token)) and not re.fullmatch(
        r"[A-Za-zµ°]{1,6}/[A-Za-z]{1,6}", token.rstrip(",.*")
    )


def close_spans(line, open_tick):
    """The line with its code spans blanked, also one that began on the line before
    (`open_tick`) or goes on to the next (then the second value is True)."""
    probe = re.sub(r"``.*?``|`[^`]*`", lambda m: " " * len(m.group()), ("`" if open_tick else "") + line)
    k = probe.find("`")
    if k >= 0:
        probe = probe[:k] + " " * (len(probe) - k)
    return probe[1:] if open_tick else probe, k >= 0


def cell_of(line, pos):
    """The text of the table cell of `line` that holds column `pos`."""
    left = line.rfind("|", 0, pos)
    right = line.find("|", pos)
    return line[left + 1 : right if right >= 0 else len(line)]


def figures_in(line):
    """[(column, number, figure)] of one line of prose or table: `number` as written, `figure`
    with its unit, percent sign or "of M"."""
    s = prose_of(line)
    table = s.lstrip().startswith("|")
    out, done = [], 0
    for m in FIG.finditer(s):
        start, end = m.start(), m.end()
        if start < done:
            continue
        num, tail, after = m.group("num"), m.group("tail"), s[end:]
        before = s[:start]
        if before.endswith("-") and re.search(r"[A-Za-z]-$", before):
            continue  # part of a name: exp1-2
        if re.match(r"-[A-Za-z]|\.\d|:\d|[A-Za-z]", after) and not tail:
            unit = UNIT.match(after)
            if not (unit and re.match(r"[A-Za-z]", after)):
                continue  # 2-core, 3D, 2nd, 10:30
        kind = None
        if tail or "." in num or "," in num:
            kind = "figure"
        elif re.search(r"\bp\s*[=<>≤]\s*$", before):
            kind = "p"
        if not tail:
            unit = UNIT.match(after)
            of = OF.match(after)
            if of:
                kind, end = "of", end + of.end()
            elif unit:
                kind, end = kind or "unit", end + unit.end()
        if not kind and table and cell_of(s, start).replace("*", "").strip() == s[start:end]:
            kind = "cell"
        if kind:
            out.append((start, num, line[start:end].strip()))
            done = end
    return out


def block_lines(lines):
    """Indexes of the lines inside generated blocks (markers included), and those inside this
    scanner's own block."""
    comments = {i: ln.strip() for i, ln in enumerate(lines) if re.fullmatch(r"<!--.*-->", ln.strip())}
    inside, own = set(), set()
    order = sorted(comments)
    for i in order:
        if any(i in s for s in (inside, own)):
            continue
        c = comments[i]
        m = re.match(r"<!--\s*(.+?)\s*:\s*begin\b", c)
        if m:
            close = re.compile(rf"<!--\s*{re.escape(m.group(1))}\s*:\s*end\b")
        else:
            name = c[4:-3].strip()
            close = re.compile(rf"<!--\s*end\s+{re.escape(name)}\s*-->")
        end = next((j for j in order if j > i and close.match(comments[j])), None)
        if end is not None:
            (own if c == BEGIN else inside).update(range(i, end + 1))
    return inside, own


def code_lines(lines):
    """Indexes of lines in fenced or indented code, or in a comment over several lines."""
    out, fence, comment = set(), None, False
    for i, ln in enumerate(lines):
        s = ln.strip()
        if comment:
            out.add(i)
            comment = "-->" not in s
        elif fence:
            out.add(i)
            if s.startswith(fence):
                fence = None
        elif re.match(r"(`{3,}|~{3,})", s):
            fence = re.match(r"(`{3,}|~{3,})", s).group(1)
            out.add(i)
        elif s.startswith("<!--") and "-->" not in s:
            out.add(i)
            comment = True
        elif re.match(r" {4,}\S|\t", ln) and i and (not lines[i - 1].strip() or i - 1 in out):
            out.add(i)
    return out


def whole_tables(lines, naming):
    """Indexes of the lines of parameter tables that a test checks as a whole: one of the test
    files `naming` the page quotes the heading line of the table's section."""
    out, heading, i = set(), "", 0
    while i < len(lines):
        ln = lines[i]
        if re.match(r"#+\s", ln):
            heading = ln.strip()
        cells = [c.strip().strip("*").lower() for c in ln.strip().strip("|").split("|")]
        if ln.lstrip().startswith("|") and cells[0] in WHOLE_TABLE:
            j = i
            while j < len(lines) and lines[j].lstrip().startswith("|"):
                j += 1
            if heading and any(heading in t.text for t in naming):
                out.update(range(i, j))
            i = j
            continue
        i += 1
    return out


def normal(text):
    """The words of `text`: ** dropped, quotes, brackets and punctuation stripped from their ends."""
    return [w.strip("\"'()[],;:.") for w in text.replace("**", "").split()]


def grams(words, n=WINDOW):
    return {" ".join(words[k : k + n]) for k in range(max(0, len(words) - n + 1))}


def distinctive(stretch, wordy=3):
    """Whether a stretch has at least `wordy` words of letters."""
    return sum(bool(re.search(r"[A-Za-z]{2}", w)) for w in stretch.split(" ")) >= wordy


class CheckFile:
    """One test file: its text, its numbers and its stretches of words."""

    def __init__(self, path):
        self.path = path
        with open(path, encoding="utf-8", errors="replace") as f:
            self.text = f.read()
        # adjacent string literals over lines, "a "\n "b", read as one: "a b"
        joined = re.sub(r"([\"'])\s*\n\s*(?:f|r|rf|fr)?\1", "", self.text)
        words = normal(joined)
        self.windows = grams(words)
        self.short = {g for g in grams(words, SHORT) if distinctive(g, 2)}
        self.masked = {g for g in grams(normal(PLACEHOLDER.sub(MASK, joined))) if MASK in g and distinctive(g)}
        self.numbers = set(re.findall(r"\d+(?:[.,]\d+)*", self.text))
        self._names = {}

    def names(self, page):
        """Whether the file names the page (its file name, e.g. design-loop.md; a study record also by
        `record("SLUG")`, tests/doc_pages.py)."""
        if page not in self._names:
            found = re.search(rf"(?<![\w-]){re.escape(page)}", self.text) is not None
            slug = re.match(r"^\d{4}-\d{2}-\d{2}-(.+)\.md$", page)  # a study record, named by tests/doc_pages.record
            if slug and not found:
                found = re.search(rf"record\(\s*[\"']{re.escape(slug.group(1))}[\"']\s*\)", self.text) is not None
            self._names[page] = found
        return self._names[page]

    def quotes(self, num):
        """Whether the file holds `num` as written (or without its commas), not inside a longer
        number."""
        return num in self.numbers or num.replace(",", "") in self.numbers


class Checks:
    """The test files, with the 6-word stretches of all of them (rules b and c)."""

    def __init__(self, paths):
        self.files = [CheckFile(p) for p in sorted(paths)]
        self.windows = set().union(*(t.windows for t in self.files))
        self.masked = set().union(*(t.masked for t in self.files))

    def naming(self, page):
        return [t for t in self.files if t.names(page)]


def read_checks(repo):
    return Checks(
        glob.glob(os.path.join(repo, "tests", "*.py"))
        + glob.glob(os.path.join(repo, "catkin_ws", "src", "*", "test", "*.py"))
    )


def pages_of(repo):
    readme = os.path.join(repo, "README.md")
    return ([readme] if os.path.exists(readme) else []) + sorted(
        glob.glob(os.path.join(repo, "docs", "*.md")) + glob.glob(os.path.join(repo, "docs", "studies", "*.md"))
    )


def significant(num):
    """Digits of `num` that say something: not leading zeros, nor an integer's trailing zeros
    (0.048 -> 2, 300 -> 1, 1,477 -> 4, 2.50 -> 3)."""
    digits = num.replace(",", "").replace(".", "").lstrip("0")
    return len(digits if "." in num else digits.rstrip("0"))


def kind_of(num, idx, words, masked, naming, tests):
    """("checked", rule) or ("left", None) for a figure outside generated blocks."""
    if significant(num) >= MIN_DIGITS and any(t.quotes(num) for t in naming):
        return "checked", "a"
    if idx is None:
        return "left", None

    def stretches(of, n):
        return [" ".join(of[k : k + n]) for k in range(max(0, idx - n + 1), min(idx, len(of) - n) + 1)]

    if any(s in tests.windows for s in stretches(words, WINDOW)):
        return "checked", "b"
    if any(s in t.short for s in stretches(words, SHORT) for t in naming):
        return "checked", "b"
    if any(s in tests.masked for s in stretches(masked, WINDOW)):
        return "checked", "c"
    return "left", None


def scan_page(path, tests, repo=REPO):
    """Every figure of one page: dicts of page, line, figure, number, kind (checked, generated,
    left), rule (a, b or c for checked) and context."""
    with open(path, encoding="utf-8") as f:
        lines = f.read().split("\n")
    page = os.path.basename(path)
    generated, own = block_lines(lines)
    naming = tests.naming(page)
    skip = code_lines(lines) | own | whole_tables(lines, naming)
    words, found = [], []  # the page's words, for rules (b) and (c); the figures
    open_tick = False  # a code span goes on from the line before
    for i, ln in enumerate(lines):
        if i in skip or not ln.strip():
            open_tick = False
            continue
        text, open_tick = close_spans(ln, open_tick and not ln.lstrip().startswith("|"))
        spans = []
        quoted = re.sub(r"^[\s>]+", lambda m: " " * len(m.group()), ln)  # no blockquote marks
        for m in re.finditer(r"\S+", quoted.replace("**", "  ")):
            for w in normal(m.group()):
                spans.append((m.start(), m.end(), len(words)))
                words.append(w)
        for col, num, fig in figures_in(text):
            idx = next((k for s, e, k in spans if s <= col < e), None)
            found.append((i, col, num, fig, idx))
    masked = list(words)
    for _, _, num, _, idx in found:
        if idx is not None:
            masked[idx] = masked[idx].replace(num, MASK, 1)
    out = []
    for i, col, num, fig, idx in found:
        kind, rule = ("generated", None) if i in generated else kind_of(num, idx, words, masked, naming, tests)
        ln = lines[i].strip()
        col -= len(lines[i]) - len(lines[i].lstrip())
        lo = max(0, min(col - 30, len(ln) - 80))
        out.append(
            {
                "page": os.path.relpath(path, repo),
                "line": i + 1,
                "figure": fig,
                "number": num,
                "kind": kind,
                "rule": rule,
                "context": " ".join(ln[lo : lo + 80].split()),
            }
        )
    return out


def scan(repo=REPO, pages=None, tests=None):
    tests = read_checks(repo) if tests is None else tests
    return {os.path.relpath(p, repo): scan_page(p, tests, repo) for p in (pages or pages_of(repo))}


def counts(figs):
    kinds = [f["kind"] for f in figs]
    return len(kinds), kinds.count("checked"), kinds.count("generated"), kinds.count("left")


def summary(result):
    rows = ["| page | figures | checked by a test | in a generated block | left |", "|---|---|---|---|---|"]
    total = [0, 0, 0, 0]
    for page, figs in result.items():
        c = counts(figs)
        total = [a + b for a, b in zip(total, c)]
        rows.append(f"| {page} | " + " | ".join(str(n) for n in c) + " |")
    rows.append("| **all** | " + " | ".join(f"**{n}**" for n in total) + " |")
    return "\n".join(rows)


def markdown(result, examples=10):
    """The summary table, then for each page the first `examples` lines with a figure left."""
    out = [summary(result)]
    for page, figs in result.items():
        lines = {}
        for f in figs:
            if f["kind"] == "left":
                lines.setdefault(f["line"], f["context"])
        if lines:
            more = f", the first {examples}" if len(lines) > examples else ""
            out += ["", f"{page}: {len(lines)} lines with a figure left{more}:", "", "```text"]
            out += [f"{n:5d}  {c}" for n, c in list(lines.items())[:examples]] + ["```"]
    return "\n".join(out)


def plain(result):
    out = []
    for page, figs in result.items():
        n, checked, generated, left = counts(figs)
        out.append(f"{page}: {n} figures, {checked} checked by a test, {generated} in a generated block, {left} left")
        out += [f"  {f['line']:5d}  {f['figure']:<16} {f['context']}" for f in figs if f["kind"] == "left"]
    return "\n".join(out)


def block(result):
    return "\n".join([BEGIN, f"<!-- generated by `{COMMAND}`; do not edit -->", "", summary(result), "", END])


def rewrite_block(doc, block_text, check):
    """Replaces the page's block (markers included) by `block_text`; with `check`, only says
    whether it is stale (exit 1). Exit 2 when the page has no such block."""
    with open(doc, encoding="utf-8") as f:
        text = f.read()
    if BEGIN not in text or END not in text:
        print(f"doc_figures: {doc} has no {BEGIN} ... {END} block", file=sys.stderr)
        return 2
    new = text[: text.index(BEGIN)] + block_text + text[text.index(END) + len(END) :]
    if check:
        if new != text:
            print(f"doc_figures: {doc}'s block is stale: run {COMMAND}", file=sys.stderr)
        return 0 if new == text else 1
    with open(doc, "w", encoding="utf-8") as f:
        f.write(new)
    return 0


def main(argv=None):
    p = argparse.ArgumentParser(prog="doc_figures", description=__doc__.split("\n\n")[0])
    p.add_argument("--markdown", action="store_true", help="summary table and up to 10 lines left a page")
    p.add_argument("--json", metavar="FILE", help="write every figure with its kind to FILE")
    p.add_argument("--doc", metavar="PAGE", help="rewrite the summary block of PAGE (docs/testing.md)")
    p.add_argument("--check", action="store_true", help="with --doc: exit 1 if the block is stale")
    p.add_argument("--repo", default=REPO, help=argparse.SUPPRESS)
    a = p.parse_args(argv)
    if a.check and not a.doc:
        p.error("--check needs --doc")
    result = scan(a.repo)
    if a.json:
        with open(a.json, "w", encoding="utf-8") as f:
            json.dump(
                {
                    "summary": {
                        k: dict(zip(("figures", "checked", "generated", "left"), counts(v))) for k, v in result.items()
                    },
                    "figures": [f for v in result.values() for f in v],
                },
                f,
                indent=1,
            )
    if a.doc:
        doc = a.doc if os.path.isabs(a.doc) or os.path.exists(a.doc) else os.path.join(a.repo, a.doc)
        return rewrite_block(doc, block(result), a.check)
    if not a.json:
        print(markdown(result) if a.markdown else plain(result))
    elif a.markdown:
        print(markdown(result))
    return 0


if __name__ == "__main__":
    sys.exit(main())
