"""Reading a campaign's rows for a study (issue #78): compact exports or a store's campaign, the
experiment it ran and what it counted as a finding. No ROS."""

import json
import os
import tempfile
from typing import List, Optional, Tuple


def read_rows(exports: List[str], store: str = "", campaign: str = "") -> Tuple[List[dict], dict]:
    """(rows, campaign row) of compact exports (of one experiment) or of a store's campaign (by
    default the one that stored a scenario last)."""
    from asg_agent.records.export import export, read_export

    if store:
        from asg_agent.records.store import Store

        if not os.path.exists(store):
            raise ValueError(f"store {store}: no such file")
        campaign = campaign or latest_campaign(store)
        with tempfile.TemporaryDirectory() as tmp:
            path = os.path.join(tmp, "c.jsonl.gz")
            export(Store(store), campaign, path)
            camp, rows = read_export(path)
            return [dict(x, _campaign=campaign) for x in rows], camp
    if not exports:
        raise ValueError("no export given")
    rows, camp = [], None
    for path in exports:
        c, r = read_export(path)
        if camp is not None and not same_experiment(c, camp):
            raise ValueError(f"{path}: another experiment than {exports[0]}'s")
        camp = camp or c
        rows += [dict(x, _campaign=c.get("name", path)) for x in r]
    return rows, camp


def same_experiment(a: dict, b: dict) -> bool:
    """Whether two campaigns ran the same experiment: the same keys and values of the experiment
    file they stored (its comments aside: a reworded header is the same experiment)."""
    import yaml

    ta, tb = a.get("experiment_text"), b.get("experiment_text")
    return ta == tb or (ta is not None and tb is not None and yaml.safe_load(ta) == yaml.safe_load(tb))


def latest_campaign(store: str) -> str:
    """The campaign of the store that stored a scenario last (the one just run)."""
    import sqlite3

    db = sqlite3.connect(f"file:{store}?mode=ro", uri=True)
    try:
        row = db.execute("SELECT campaign FROM scenarios ORDER BY finished DESC LIMIT 1").fetchone()
    except sqlite3.DatabaseError as e:
        raise ValueError(f"store {store}: {e}") from None
    finally:
        db.close()
    if row is None:
        raise ValueError(f"store {store}: holds no scenario")
    return row[0]


def settings_of(camp: dict) -> dict:
    s = camp.get("settings") or {}
    return json.loads(s) if isinstance(s, str) else s


def experiment_of(camp: dict):
    """The experiment a campaign ran: its repository file, else the text it stored."""
    from asg_agent.paths import REPO
    from asg_agent.records.experiment import load_experiment

    s = settings_of(camp)
    rel = s.get("experiment_repo_file") or s.get("experiment_file") or ""
    path = rel if os.path.isabs(rel) else os.path.join(REPO, rel)
    if rel and os.path.exists(path):
        return load_experiment(path)
    raise ValueError(f"campaign {camp.get('name')!r}: its experiment file {rel!r} is not in this checkout")


def target_of(camp: dict) -> Optional[str]:
    """What the campaign counted as a finding: its reward's class (flaw, regression), or None for
    the stack's own failures."""
    s = settings_of(camp)
    roles = s.get("references") or {}
    if s.get("reward") in ("flaw", "regression"):
        return s["reward"]
    if "full" in roles:  # three-stack attribution: its flaw findings, whatever the search maximised
        return "flaw"
    if "release" in roles:
        return "regression"
    return None
