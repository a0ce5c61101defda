"""Issue #68: committed records hold repository-relative paths only. Every file git tracks under
results/ (gzip files read decompressed; binary files skipped: pictures, model
weights, TensorBoard event files; SQLite databases read as their SQL text and tar archives member
by member since issue #79) is scanned for a path of a machine: an absolute path whose first
folder is one where a checkout, a home or scratch data lives (/work/, /root/, /home/, /tmp/,
/usr/local/, /old_root/, /mnt/, /media/, /Users/, /scratch/). Such a path means nothing on
another machine; a record names a file of the repository relative to its root
(`experiments/exp1.yaml`, as an export's `experiment_file` does; asg_agent.paths.in_repo resolves
it), or as `$REPO/...` in a log.

Not a machine's path, so not matched: a path inside a word or a file name (`a/tmp/b`, `x.tmp/`),
`$REPO/...` and `~/...`, ROS names (`/worker_0/planner`), and system paths that are the same on
every machine (`/usr/bin/python3`, `/opt/ros/...`).

Allowed where listed (ALLOWED): the names of scratch folders under /tmp/ that a measurement read
its frames from, or where the fuzzer kept its failing inputs; they say where data lay during the
run, are gone after it, and no reader resolves them."""

import fnmatch
import gzip
import os
import re
import subprocess

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))

#: the first folders of a machine's checkouts, homes and scratch data
FOLDERS = ("work", "root", "home", "tmp", "usr/local", "old_root", "mnt", "media", "Users", "scratch")

#: an absolute path under one of FOLDERS, not preceded by a word character, a dot, `$`
#: (`$REPO/...`), `~` or `-` (then it is part of a longer name), up to a space, quote or separator
MACHINE_PATH = re.compile(rb"(?<![\w.$~-])/(?:" + b"|".join(f.encode() for f in FOLDERS) + rb")/[^\s\"'\\,;)\]\x00]*")

#: files (fnmatch patterns) where paths under a prefix are allowed, with why
ALLOWED = {
    "results/numerics/polyphase_agreement.json": ("/tmp/", "the scratch folders of the frames it compared"),
    "results/perception_spread/seed_*.json": ("/tmp/", "the mktemp folder of the frames it segmented"),
    "results/perception_spread/lite/seed_*.json": ("/tmp/", "the mktemp folder of the frames it segmented"),
    "results/reliability/fuzz_loaders*.json": ("/tmp/", "the folder where the fuzzer kept its inputs"),
}

#: binary files: nothing in them is a record's text
BINARY = (
    ".png",
    ".jpg",
    ".pdf",
    ".sqlite",
    ".sqlite3",
    ".db",
    ".xz",
    ".tar",
    ".zip",
    ".pt",
    ".pth",
    ".npz",
    ".npy",
    ".bag",
)


def committed(folder: str = "results") -> list:
    """The files git tracks under `folder` (repository-relative)."""
    out = subprocess.run(["git", "ls-files", "-z", folder], cwd=REPO, capture_output=True, check=True).stdout
    return [p for p in out.decode().split("\0") if p]


def sqlite_text(data: bytes) -> bytes:
    """The SQL text of an SQLite database's every table and row (blobs as hex: no path in them)."""
    import sqlite3
    import tempfile

    with tempfile.NamedTemporaryFile(suffix=".sqlite") as f:
        f.write(data)
        f.flush()
        db = sqlite3.connect(f.name)
        try:
            return "\n".join(db.iterdump()).encode("utf-8", "replace")
        finally:
            db.close()


def archive_text(path: str, data: bytes) -> bytes:
    """The text of every member of a tar archive (issue #79: a parked store is one), each read as
    a committed file of its name would be: a database as its SQL text, a checkpoint (pickled) as
    its bytes, whose strings a path would show in."""
    import io
    import tarfile

    parts = []
    with tarfile.open(fileobj=io.BytesIO(data)) as tar:
        for m in tar.getmembers():
            if m.isfile():
                body = tar.extractfile(m).read()
                name = f"{path}/{m.name}"
                parts.append(body if name.endswith((".ckpt", ".pkl")) else text_of(name, body) or b"")
    return b"\n".join(parts)


def text_of(path: str, data: bytes):
    """The bytes to scan of a committed file (`data` as stored): gzip decompressed, an SQLite
    database as its SQL text, a tar archive (`.tar`, `.tar.xz`, `.tar.gz`) as its members' text;
    None for another binary file (by its name, a TensorBoard event file, or a NUL byte in it)."""
    if path.endswith((".sqlite", ".sqlite3", ".db")):
        return sqlite_text(data)
    if path.endswith((".tar", ".tar.xz", ".tar.gz", ".tgz")):
        return archive_text(path, data)
    if path.endswith(BINARY) or "tfevents" in os.path.basename(path):
        return None
    if path.endswith(".gz"):
        data = gzip.decompress(data)
    return None if b"\0" in data else data


def machine_paths(path: str, data: bytes) -> list:
    """The machine paths (MACHINE_PATH) in the file `path` whose stored bytes are `data`, less
    those ALLOWED there, in order."""
    text = text_of(path, data)
    # most files (the exports' rows) hold none of the folders at all: a fast test first
    if text is None or not any(f"/{d}/".encode() in text for d in FOLDERS):
        return []
    allowed = [prefix for pattern, (prefix, _) in ALLOWED.items() if fnmatch.fnmatch(path, pattern)]
    return [
        m.group(0).decode("utf-8", "replace")
        for m in MACHINE_PATH.finditer(text)
        if not any(m.group(0).startswith(p.encode()) for p in allowed)
    ]


def offenders(read=lambda p: open(os.path.join(REPO, p), "rb").read()) -> dict:
    """{file: [machine paths]} of the committed files under results/, read by `read(path)`."""
    out = {}
    for p in committed():
        try:
            data = read(p)
        except FileNotFoundError:  # deleted in the working tree, not yet committed
            continue
        found = machine_paths(p, data)
        if found:
            out[p] = found
    return out


def test_committed_records_hold_no_machine_paths():
    bad = offenders()
    assert not bad, (
        f"{len(bad)} file(s) under results/ hold a machine's absolute path (make it repository-relative):\n"
        + "\n".join(
            f"  {p}: {found[0]!r}" + (f" (and {len(found) - 1} more)" if len(found) > 1 else "")
            for p, found in sorted(bad.items())
        )
    )


def test_the_rule_tells_a_machine_path_from_others():
    hit = lambda s: machine_paths("results/x.json", s.encode())  # noqa: E731
    assert hit('"experiment_file": "/work/main/experiments/exp1.yaml"') == ["/work/main/experiments/exp1.yaml"]
    assert hit('{\\"experiment_file\\": \\"/root/asg/experiments/exp1.yaml\\"}') == ["/root/asg/experiments/exp1.yaml"]
    assert hit("kept /tmp/asg_fuzz_x/a.yaml, /home/me/x") == ["/tmp/asg_fuzz_x/a.yaml", "/home/me/x"]
    for fine in (
        "experiments/exp1.yaml",
        "$REPO/results/x.log",
        "~/catkin_ws",
        "/worker_0/planner",
        "/usr/bin/python3 -m pytest",
        "/opt/ros/noetic/setup.bash",
        "https://example.org/home/page",
        "a/tmp/b and x.tmp/y",
    ):
        assert hit(fine) == [], fine
    # allowed only where listed, and only under its prefix
    assert machine_paths("results/perception_spread/seed_3.json", b'"data": "/tmp/tmp.abc"') == []
    assert machine_paths("results/perception_spread/seed_3.json", b'"data": "/work/main/x"') == ["/work/main/x"]
    # a gzip file is read decompressed; a binary one is skipped
    assert machine_paths("results/a.jsonl.gz", gzip.compress(b'{"f": "/work/main/x"}\n')) == ["/work/main/x"]
    assert machine_paths("results/a.png", b"/work/main/x") == []
    # a database is read as its rows, an archive member by member (issue #79: a parked store)
    import io
    import sqlite3
    import tarfile
    import tempfile

    with tempfile.TemporaryDirectory() as d:
        db = sqlite3.connect(os.path.join(d, "s.sqlite"))
        db.execute("CREATE TABLE campaigns (settings TEXT)")
        db.execute("""INSERT INTO campaigns VALUES ('{"experiment_file": "/work/main/experiments/exp5.yaml"}')""")
        db.commit()
        db.close()
        store = open(os.path.join(d, "s.sqlite"), "rb").read()
    assert machine_paths("results/s.sqlite", store) == ["/work/main/experiments/exp5.yaml"]
    buf = io.BytesIO()
    with tarfile.open(fileobj=buf, mode="w:xz") as tar:
        for name, body in (("store.sqlite", store), ("checkpoint.ckpt", b"\x80\x04/root/x.yaml\x00")):
            info = tarfile.TarInfo(name)
            info.size = len(body)
            tar.addfile(info, io.BytesIO(body))
    assert machine_paths("results/p.tar.xz", buf.getvalue()) == ["/work/main/experiments/exp5.yaml", "/root/x.yaml"]
