"""Scenario store: SQLite in WAL mode, one row per scenario written as it finishes (no ROS).

Tables (docs/agent.md has every column):
- campaigns: one row per campaign (name, experiment file text, method, seed, settings).
- scenarios: one row per finished scenario. (campaign, job) is unique: a campaign can never
  count a scenario twice, also across resumes. The trajectory is stored compressed (zlib of
  float32 columns t, x, y, yaw, yaw rate), the request as canonical JSON, so any row can be
  replayed exactly and every figure recomputed without simulating.
"""

import json
import os
import shutil
import sqlite3
import time
import zlib
from typing import Dict, Iterator, List, Optional

import numpy as np

SCHEMA = """
CREATE TABLE IF NOT EXISTS campaigns (
  name TEXT PRIMARY KEY,
  method TEXT NOT NULL,
  experiment TEXT NOT NULL,        -- the experiment file's name field
  experiment_text TEXT NOT NULL,   -- the experiment file as read
  seed INTEGER NOT NULL,
  settings TEXT NOT NULL,          -- JSON: total, workers, method config, stack
  created REAL NOT NULL,
  finished REAL
);
CREATE TABLE IF NOT EXISTS scenarios (
  id INTEGER PRIMARY KEY AUTOINCREMENT,
  campaign TEXT NOT NULL REFERENCES campaigns(name),
  job INTEGER NOT NULL,            -- 0-based sequence number of the proposal in its campaign
  method TEXT NOT NULL,
  episode INTEGER NOT NULL,
  step INTEGER NOT NULL,
  worker TEXT NOT NULL,
  attempts INTEGER NOT NULL,       -- runs it took (> 1 after an ERROR retried elsewhere)
  scenario_id INTEGER NOT NULL,
  request TEXT NOT NULL,           -- canonical scenario JSON, exactly what was sent
  termination TEXT NOT NULL,       -- SUCCESS, COLLISION, ..., ERROR
  error TEXT NOT NULL,
  proxy REAL, vis REAL, yaw_term REAL, plr REAL,
  path_length REAL, optimal_length REAL,
  sim_time REAL NOT NULL,
  num_control_msgs INTEGER NOT NULL,
  visibility TEXT NOT NULL,        -- JSON list, per instance
  removed TEXT NOT NULL,           -- JSON list of [layout, instance, reason]
  collision_with TEXT NOT NULL,
  trajectory BLOB NOT NULL,        -- zlib(float32[n, 5]: t, x, y, yaw, yaw rate)
  samples INTEGER NOT NULL,
  wall_time REAL NOT NULL,         -- [s] goal sent to result received (last attempt)
  finished REAL NOT NULL,          -- unix time
  UNIQUE (campaign, job)
);
CREATE INDEX IF NOT EXISTS scenarios_proxy ON scenarios (campaign, proxy);
"""

COLUMNS = (
    "campaign",
    "job",
    "method",
    "episode",
    "step",
    "worker",
    "attempts",
    "scenario_id",
    "request",
    "termination",
    "error",
    "proxy",
    "vis",
    "yaw_term",
    "plr",
    "path_length",
    "optimal_length",
    "sim_time",
    "num_control_msgs",
    "visibility",
    "removed",
    "collision_with",
    "trajectory",
    "samples",
    "wall_time",
    "finished",
    "reference",
    "reward",
    "reference_runs",
    "attribution",
)
# Columns added after the first stores were written: (name, SQL type); added to an older store
# when it is opened.
ADDED = (
    ("reference", "TEXT"),  # differential campaigns: JSON of the reference stack's run
    ("reward", "REAL"),  # what the search learnt from: the proxy, or proxy - reference proxy
    # Attribution on named reference stacks (issue #36): JSON {role: the reference run} of every
    # reference the scenario ran on (NULL: not re-run), and its class (scoring/attribution.py:
    # flaw, model, stack, ..., not_candidate, pending).
    ("reference_runs", "TEXT"),
    ("attribution", "TEXT"),
)


# Attribution: the rule and its thresholds live in scoring/attribution.py (re-exported here for
# the modules that read them from the store).
from asg_agent.scoring.attribution import (  # noqa: E402
    DIFFERENTIAL,
    FINDING,
    FINDING_STRONG,
    PENDING,
    REFERENCE_CLEAR,
    attribute,
    count_classes,
)

__all__ = ["DIFFERENTIAL", "FINDING", "REFERENCE_CLEAR", "attribute", "Store", "StoreError"]


class StoreError(RuntimeError):
    pass


def pack_trajectory(traj: np.ndarray) -> bytes:
    traj = np.asarray(traj, dtype=np.float32).reshape(-1, 5)
    return zlib.compress(traj.tobytes(), 6)


def kept_xy(trajectory) -> list:
    """The positions attribution stores of a reference run: every 6th sample (10 Hz), to 1 cm."""
    return np.round(np.asarray(trajectory, np.float32).reshape(-1, 5)[::6, 1:3], 2).tolist()


def scenario_row(campaign: str, method: str, job, o, traj: np.ndarray, terms, reward, label) -> Dict:
    """The store's row of a finished scenario: `job` as the campaign proposed it (job, episode,
    step, attempts, request), `o` the pool's Outcome, `traj` its trajectory, `terms` its proxy terms
    (scoring.proxy; None without), `reward` what the search learns from, `label` its attribution."""
    import json
    import time

    from asg_agent.scoring.proxy import term_values

    return {
        "campaign": campaign,
        "job": o.job,
        "method": method,
        "episode": job.episode,
        "step": job.step,
        "worker": o.worker,
        "attempts": job.attempts,
        "scenario_id": job.request["scenario_id"],
        "request": json.dumps(job.request, sort_keys=True),
        "termination": o.termination,
        "error": o.error,
        **term_values(terms),
        "path_length": terms.path_length if terms else None,
        "optimal_length": terms.optimal_length if terms else None,
        "sim_time": o.sim_time,
        "num_control_msgs": o.num_control_msgs,
        "visibility": json.dumps([float(v) for v in o.visibility]),
        "removed": json.dumps(o.removed),
        "collision_with": o.collision_with,
        "trajectory": pack_trajectory(traj),
        "samples": len(traj),
        "wall_time": o.wall_time,
        "finished": time.time(),
        "reference": None,
        "reward": reward,
        "reference_runs": None,
        "attribution": label,
    }


def unpack_trajectory(blob: bytes) -> np.ndarray:
    return np.frombuffer(zlib.decompress(blob), dtype=np.float32).reshape(-1, 5)


class Store:
    def __init__(self, path: str, create: bool = True):
        """Opens (create=True: or makes) the store at `path`. Readers pass create=False: a path
        that names no file is then a StoreError, not a new empty store left behind."""
        self.path = path
        if not create and not os.path.isfile(path):
            raise StoreError(f"{path}: no such scenario store")
        folder = os.path.dirname(os.path.abspath(path))
        os.makedirs(folder, exist_ok=True)
        try:
            self.db = sqlite3.connect(path, timeout=30.0, isolation_level=None)
            self.db.row_factory = sqlite3.Row
            self.db.execute("PRAGMA journal_mode=WAL")
            self.db.execute("PRAGMA synchronous=NORMAL")
            self.db.executescript(SCHEMA)
            have = {r[1] for r in self.db.execute("PRAGMA table_info(scenarios)")}
            for name, kind in ADDED:
                if name not in have:
                    self.db.execute(f"ALTER TABLE scenarios ADD COLUMN {name} {kind}")
        except sqlite3.DatabaseError as e:
            raise StoreError(f"{path}: not a usable scenario store ({e})") from None

    def close(self):
        self.db.close()

    def integrity_ok(self) -> bool:
        return self.db.execute("PRAGMA integrity_check").fetchone()[0] == "ok"

    # -- campaigns ------------------------------------------------------------------------------
    def campaign(self, name: str) -> Optional[dict]:
        row = self.db.execute("SELECT * FROM campaigns WHERE name = ?", (name,)).fetchone()
        return dict(row) if row else None

    def campaign_names(self) -> List[str]:
        return [r[0] for r in self.db.execute("SELECT name FROM campaigns ORDER BY name")]

    def create_campaign(self, name, method, experiment, experiment_text, seed, settings: dict):
        try:
            self.db.execute(
                "INSERT INTO campaigns VALUES (?, ?, ?, ?, ?, ?, ?, NULL)",
                (name, method, experiment, experiment_text, seed, json.dumps(settings, sort_keys=True), time.time()),
            )
        except sqlite3.IntegrityError:
            raise StoreError(
                f"campaign {name!r} already exists in {self.path}: --resume it or choose another " f"--name"
            ) from None

    def record_event(self, name: str, event: Dict):
        """Appends `event` (a start, resume or restart, with the machine and code it ran on:
        provenance()) to the campaign's settings["events"], so that an export lists every
        interruption of its campaign (issues #54, #57)."""
        row = self.db.execute("SELECT settings FROM campaigns WHERE name = ?", (name,)).fetchone()
        if row is None:
            raise StoreError(f"no campaign {name!r} in {self.path}")
        settings = json.loads(row[0])
        settings.setdefault("events", []).append(event)
        self.db.execute(
            "UPDATE campaigns SET settings = ? WHERE name = ?", (json.dumps(settings, sort_keys=True), name)
        )

    def finish_campaign(self, name):
        self.db.execute("UPDATE campaigns SET finished = ? WHERE name = ?", (time.time(), name))

    # -- scenarios ------------------------------------------------------------------------------
    def add(self, row: Dict):
        """Writes one finished scenario (one transaction). A second row for the same job raises."""
        values = [row[c] for c in COLUMNS]
        try:
            self.db.execute(
                f"INSERT INTO scenarios ({', '.join(COLUMNS)}) VALUES ({', '.join('?' * len(COLUMNS))})", values
            )
        except sqlite3.IntegrityError:
            raise StoreError(f"campaign {row['campaign']!r} already holds job {row['job']}") from None

    def set_references(self, campaign: str, job: int, reference_runs: str, attribution: str, reference, reward):
        """Attaches a candidate's reference runs (JSON {role: run}), its class, the legacy
        single-reference column (the ground-truth run's JSON, or None) and the reward the search
        learns from (the proxy unless the reward needs the references)."""
        cur = self.db.execute(
            "UPDATE scenarios SET reference_runs = ?, attribution = ?, reference = ?, reward = ? "
            "WHERE campaign = ? AND job = ?",
            (reference_runs, attribution, reference, reward, campaign, job),
        )
        if cur.rowcount != 1:
            raise StoreError(f"campaign {campaign!r} holds no job {job} to attach reference runs to")

    def pending_references(self, campaign: str) -> List[sqlite3.Row]:
        """Candidates whose reference runs are not all in (a resume re-runs them)."""
        return self.db.execute(
            "SELECT * FROM scenarios WHERE campaign = ? AND attribution = ? ORDER BY job", (campaign, PENDING)
        ).fetchall()

    def classes(self, campaign: str) -> Dict[str, int]:
        """Scenarios per attribution class (scoring/attribution.py), zeros included."""
        return count_classes(
            r[0]
            for r in self.db.execute(
                "SELECT attribution FROM scenarios WHERE campaign = ? AND attribution IS NOT NULL", (campaign,)
            )
        )

    def rows(self, campaign: str, after_job: int = -1) -> Iterator[sqlite3.Row]:
        yield from self.db.execute(
            "SELECT * FROM scenarios WHERE campaign = ? AND job > ? ORDER BY job", (campaign, after_job)
        )

    def jobs(self, campaign: str) -> List[int]:
        return [r[0] for r in self.db.execute("SELECT job FROM scenarios WHERE campaign = ? ORDER BY job", (campaign,))]

    def count(self, campaign: str) -> int:
        return self.db.execute("SELECT COUNT(*) FROM scenarios WHERE campaign = ?", (campaign,)).fetchone()[0]

    def summary(self, campaign: str, top: int = 10) -> dict:
        q = self.db.execute
        n = q("SELECT COUNT(*) FROM scenarios WHERE campaign = ?", (campaign,)).fetchone()[0]
        c3 = q("SELECT COUNT(*) FROM scenarios WHERE campaign = ? AND proxy >= ?", (campaign, FINDING)).fetchone()[0]
        c4 = q(
            "SELECT COUNT(*) FROM scenarios WHERE campaign = ? AND proxy >= ?", (campaign, FINDING_STRONG)
        ).fetchone()[0]
        best = q("SELECT MAX(proxy) FROM scenarios WHERE campaign = ?", (campaign,)).fetchone()[0]
        terms = dict(
            q(
                "SELECT termination, COUNT(*) FROM scenarios WHERE campaign = ? GROUP BY termination", (campaign,)
            ).fetchall()
        )
        tops = [
            dict(r)
            for r in q(
                "SELECT id, job, episode, step, scenario_id, proxy, vis, yaw_term, plr, termination "
                "FROM scenarios WHERE campaign = ? AND proxy IS NOT NULL ORDER BY proxy DESC, "
                "job LIMIT ?",
                (campaign, top),
            )
        ]
        # Attribution (campaigns with a reference stack): a finding (proxy >= 3) is the perception's
        # when the reference stack (ground-truth labels, same planner and follower) stays below 2
        # on the same scene, and the stack's own when the reference reaches 3 as well.
        ref = "CAST(json_extract(reference, '$.proxy') AS REAL)"
        F, C = FINDING, REFERENCE_CLEAR  # attribute(), in SQL
        attributed = q(
            f"SELECT COUNT(*), SUM(proxy >= {F} AND {ref} < {C}), SUM(proxy >= {F} AND {ref} >= {F}), "
            f"SUM(proxy - {ref} >= {DIFFERENTIAL}) FROM scenarios WHERE campaign = ? AND reference IS NOT NULL "
            f"AND proxy IS NOT NULL AND {ref} IS NOT NULL",
            (campaign,),
        ).fetchone()
        # A collision of the stack under test where the reference stack drove through the same
        # scene: the perception's fault whatever the proxy says (the paper's proxy does not score
        # collisions), and the stack's when both collide.
        rterm = "json_extract(reference, '$.termination')"
        collided = q(
            f"SELECT SUM(termination = 'COLLISION' AND {rterm} = 'SUCCESS'), "
            f"SUM(termination = 'COLLISION' AND {rterm} = 'COLLISION') FROM scenarios "
            f"WHERE campaign = ? AND reference IS NOT NULL",
            (campaign,),
        ).fetchone()
        # A run that reached the goal shorter than the optimal path means the optimal path is
        # wrong. A run that ended early may (its rest is a straight line, through what it hit).
        low_plr = q(
            "SELECT COUNT(*) FROM scenarios WHERE campaign = ? AND plr < 0.999 AND termination = 'SUCCESS'",
            (campaign,),
        ).fetchone()[0]
        return {
            "scenarios": n,
            "proxy_ge_3": c3,
            "proxy_ge_4": c4,
            "max_proxy": best,
            "terminations": terms,
            "top": tops,
            "attributed": attributed[0],
            "perception_ge3": attributed[1] or 0,
            "stack_ge3": attributed[2] or 0,
            "differential_ge1": attributed[3] or 0,
            "plr_below_0999": low_plr,
            "perception_collisions": collided[0] or 0,
            "stack_collisions": collided[1] or 0,
            "classes": self.classes(campaign),
        }

    def content_digest(self, campaign: str) -> List[tuple]:
        """What must repeat between two runs of a campaign with one seed (no workers, no times)."""
        return [
            tuple(r)
            for r in self.db.execute(
                "SELECT job, episode, step, scenario_id, request, termination, proxy, vis, yaw_term, plr, sim_time, "
                "num_control_msgs, trajectory FROM scenarios WHERE campaign = ? ORDER BY job",
                (campaign,),
            )
        ]


# -- parking: carrying an unfinished campaign from one machine (or checkout) to another ------------
# A campaign is resumable only with its store rows and its checkpoint. `park` writes both into one
# tar.xz (a one-campaign SQLite store, trajectories uncompressed, and the checkpoint file, the whole
# xz-compressed: about 6 kB a scenario), small enough to commit; `unpark`
# puts them back into a store and beside it, and the campaign then resumes as if never moved.


def park(store: "Store", campaign: str, checkpoint: str, out: str) -> int:
    """Writes campaign `campaign` of `store` (its campaign row and every scenario row) and its
    checkpoint file into the tar.xz `out`. Returns the number of scenario rows parked."""
    import tarfile
    import tempfile

    if store.campaign(campaign) is None:
        raise StoreError(f"no campaign {campaign!r} in {store.path} to park")
    if not os.path.isfile(checkpoint):
        raise StoreError(f"{checkpoint}: no checkpoint for campaign {campaign!r} (nothing to resume from)")
    with tempfile.TemporaryDirectory() as tmp:
        one = os.path.join(tmp, "store.sqlite")
        Store(one).close()  # the schema
        db = sqlite3.connect(one, isolation_level=None)
        try:
            db.execute("ATTACH DATABASE ? AS src", (os.path.abspath(store.path),))
            db.execute("INSERT INTO campaigns SELECT * FROM src.campaigns WHERE name = ?", (campaign,))
            # Trajectories go in raw (float32 bytes): xz packs those about 5x smaller than their zlib.
            db.create_function("unzip", 1, zlib.decompress, deterministic=True)
            cols = ", ".join(COLUMNS)
            raw = cols.replace("trajectory", "unzip(trajectory)")
            db.execute(
                f"INSERT INTO scenarios ({cols}) SELECT {raw} FROM src.scenarios WHERE campaign = ? " f"ORDER BY job",
                (campaign,),
            )
            n = db.execute("SELECT COUNT(*) FROM scenarios").fetchone()[0]
            db.execute("DETACH DATABASE src")
            db.execute("PRAGMA journal_mode=DELETE")
            db.execute("VACUUM")
        finally:
            db.close()
        os.makedirs(os.path.dirname(os.path.abspath(out)), exist_ok=True)
        part = out + ".part"
        with tarfile.open(part, "w:xz") as tar:
            for path, arc in ((one, "store.sqlite"), (checkpoint, "checkpoint.ckpt")):
                info = tar.gettarinfo(path, arc)
                info.mtime, info.uid, info.gid, info.uname, info.gname = 0, 0, 0, "", ""
                with open(path, "rb") as f:
                    tar.addfile(info, f)
        os.replace(part, out)
    return n


def checkpoint_path(store_path: str, campaign: str) -> str:
    """Where a campaign's checkpoint lives: beside its store, STORE.CAMPAIGN.ckpt."""
    return os.path.splitext(os.path.abspath(store_path))[0] + f".{campaign}.ckpt"


def unpark(store: "Store", parked: str, checkpoint_for=None) -> Optional[int]:
    """Puts a parked campaign back: its rows into `store`, its checkpoint to
    checkpoint_for(campaign name). A store that already holds the campaign is left alone (returns
    None): it is the newer copy. Otherwise returns the number of scenario rows restored."""
    import tarfile
    import tempfile

    try:
        tar = tarfile.open(parked, "r:xz")
    except (OSError, tarfile.TarError) as e:
        raise StoreError(f"{parked}: not a parked campaign ({e})") from None
    with tempfile.TemporaryDirectory() as tmp, tar:
        names = set(tar.getnames())
        if names != {"store.sqlite", "checkpoint.ckpt"}:
            raise StoreError(
                f"{parked}: not a parked campaign (holds {sorted(names)}, expected store.sqlite and "
                f"checkpoint.ckpt)"
            )
        for name in names:
            with tar.extractfile(name) as src, open(os.path.join(tmp, name), "wb") as dst:
                dst.write(src.read())
        one = Store(os.path.join(tmp, "store.sqlite"))
        rows = one.db.execute("SELECT name FROM campaigns").fetchall()
        one.close()
        if len(rows) != 1:
            raise StoreError(f"{parked}: holds {len(rows)} campaigns, expected 1")
        campaign = rows[0][0]
        if store.campaign(campaign) is not None:
            return None
        cols = ", ".join(COLUMNS)
        db = store.db
        db.create_function("rezip", 1, lambda raw: zlib.compress(raw, 6), deterministic=True)  # as pack_trajectory
        db.execute("ATTACH DATABASE ? AS src", (os.path.join(tmp, "store.sqlite"),))
        try:
            db.execute("BEGIN")
            db.execute("INSERT INTO campaigns SELECT * FROM src.campaigns")
            db.execute(
                f"INSERT INTO scenarios ({cols}) SELECT {cols.replace('trajectory', 'rezip(trajectory)')} "
                f"FROM src.scenarios ORDER BY job"
            )
            db.execute("COMMIT")
        except sqlite3.DatabaseError as e:
            db.execute("ROLLBACK")
            raise StoreError(f"{parked}: could not be restored into {store.path} ({e})") from None
        finally:
            db.execute("DETACH DATABASE src")
        target = (checkpoint_for or (lambda c: checkpoint_path(store.path, c)))(campaign)
        os.makedirs(os.path.dirname(os.path.abspath(target)), exist_ok=True)
        shutil.copyfile(os.path.join(tmp, "checkpoint.ckpt"), target + ".part")
        os.replace(target + ".part", target)
        return store.count(campaign)


#: the repository this module runs from (empty commit where it is not a git checkout)
from asg_agent.paths import REPO as _REPO  # noqa: E402


def provenance() -> Dict:
    """Where and on what a campaign runs now: the time, the CPU's model name and cores, and the
    repository's commit (the code, and the protocol committed before it)."""
    import subprocess

    cpu = ""
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as f:
            cpu = next((ln.split(":", 1)[1].strip() for ln in f if ln.startswith("model name")), "")
    except OSError:
        pass
    try:
        commit = subprocess.run(
            ["git", "-C", _REPO, "rev-parse", "HEAD"], capture_output=True, text=True, timeout=10
        ).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        commit = ""
    return {"time": round(time.time(), 1), "cpu": cpu, "cores": os.cpu_count() or 0, "commit": commit}
