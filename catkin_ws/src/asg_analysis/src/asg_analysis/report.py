"""A campaign's HTML report from its store, without a display (no ROS; figures from bags of
replays are asg_agent.ros.bag_figures).

    python3 -m asg_analysis report campaign STORE CAMPAIGN OUT_DIR [--top 10]

`campaign` writes OUT_DIR/index.html (open it from disk, no server): first what the campaign
searched for (its findings, their distinct places, the rules they have in common and the best
distinct findings with their top-down figures and replay commands), then the Table-2-style counts, the proxy over scenarios with its running best and the counts >= 3 as the
campaign went on, terminations, and the top-k table with each scenario's top-down figure and
its replay command.
"""

import argparse
import html
import json
import os

import yaml
import sys

import numpy as np
from asg_agent.records.store import StoreError
from asg_agent.scoring.attribution import FINDING, FINDING_STRONG

PROG = "python3 -m asg_analysis report"


def baseline_path(experiment: str, settings: dict) -> str:
    """results/baseline/<exp>.json of the campaign's experiment, or else of its scenario (the
    depth stack's exp1-depth runs exp1's layouts: its row is in exp1.json); "" if neither."""
    from asg_agent.paths import REPO, in_repo

    names = [experiment]
    # the recorded file: repository-relative (issue #68), or absolute in older stores and exports,
    # where the repository-relative one is also recorded
    source = next(
        (
            in_repo(f)
            for f in (settings.get("experiment_file", ""), settings.get("experiment_repo_file", ""))
            if f and os.path.isfile(in_repo(f))
        ),
        "",
    )
    if source:
        with open(source, encoding="utf-8") as f:
            scenario = (yaml.safe_load(f) or {}).get("scenario", "")
        names.append(os.path.splitext(os.path.basename(str(scenario)))[0])
    for n in names:
        path = os.path.join(REPO, "results", "baseline", f"{n}.json")
        if n and os.path.isfile(path):
            return path
    return ""


def _baseline_html(experiment: str, settings: dict) -> str:
    """The baseline of the campaign's experiment (baseline_path), if measured."""
    path = baseline_path(experiment, settings)
    if not path:
        return (
            f"<h2>Baseline</h2><p>No baseline of {html.escape(experiment)} yet: "
            f"<code>bash scripts/repro/baseline.sh {html.escape(experiment)}</code> measures it.</p>"
        )
    with open(path) as f:
        b = json.load(f)
    rows = "".join(
        f"<tr><td>{html.escape(k)}</td><td>{g['runs']}</td><td>{100 * g['share_ge3']:.1f} %</td>"
        f"<td>{g['median_yaw_term']:.3f} / {g['p90_yaw_term']:.3f}</td><td>{g['median_plr']:.3f} / {g['p90_plr']:.3f}</td>"
        f"<td>{g['collisions']}</td></tr>"
        for k, g in b["stacks"].items()
    )
    return (
        f"<h2>Baseline: the stacks on seeded random layouts of {html.escape(experiment)}</h2>"
        "<table><tr><th>stack</th><th>runs</th><th>proxy &gt;= 3</th><th>yaw term median / p90</th>"
        f"<th>PLR median / p90</th><th>collisions</th></tr>{rows}</table>"
    )


def reference_words(settings: dict) -> str:
    """What the reference stack of a single-reference attribution is, against the stack under test."""
    if settings.get("stack", "paper") == "paper":
        return "ground-truth labels, the same planner and follower"
    return f"the paper's stack on ground-truth labels: another planner and follower than {settings['stack']}'s"


def _three_stack_html(store, store_path: str, campaign: str, s: dict, out_dir: str, top: int) -> str:
    """The three-stack attribution section (issue #36): the classes, and the findings of the
    stack under test (flaw first) with the three paths on the scene and the replay command."""
    from asg_analysis.figures import top_down
    from asg_agent.scoring import attribution as attr

    cl = s["classes"]
    if not sum(cl.values()):
        return ""
    rerun = sum(v for k, v in cl.items() if k != attr.NOT_CANDIDATE)
    head = "".join(f"<th>{k}</th>" for k in attr.CLASSES + (attr.NOT_CANDIDATE, attr.PENDING))
    cells = "".join(f"<td>{cl[k]}</td>" for k in attr.CLASSES + (attr.NOT_CANDIDATE, attr.PENDING))
    order = {k: i for i, k in enumerate(attr.FINDINGS)}
    from asg_agent.records import failure_modes as fm

    found = [
        dict(r)
        for r in store.db.execute(
            "SELECT job, proxy, termination, reference_runs, attribution, request, trajectory, collision_with "
            "FROM scenarios WHERE campaign = ? AND attribution IN (" + ",".join("?" * len(attr.FINDINGS)) + ")",
            (campaign, *attr.FINDINGS),
        )
    ]
    for r in found:
        r["mode"] = fm.mode_of_stored(r)
    # grouped by failure mode (records/failure_modes.py), flaw findings first
    found = sorted(found, key=lambda r: (order[r["attribution"]], r["mode"], r["job"]))[:top]
    items = []
    for r in found:
        png = f"three_job{r['job']}.png"
        top_down(store, campaign, r["job"], os.path.join(out_dir, png))
        runs = json.loads(r["reference_runs"] or "{}")
        refs = "; ".join(
            f"{k} {v['termination']} ({'n/a' if v.get('proxy') is None else format(v['proxy'], '.2f')})"
            for k, v in sorted(runs.items())
        )
        cmd = f"rosrun asg_agent replay {store_path} {campaign} {r['job']}"
        proxy = "n/a" if r["proxy"] is None else f"{r['proxy']:.2f}"
        items.append(
            f"<tr><td>{html.escape(r['attribution'])}</td><td>{html.escape(fm.label(r['mode']))}</td>"
            f"<td>{r['job']}</td><td>{html.escape(r['termination'])} "
            f"({proxy})</td><td>{html.escape(refs)}</td><td><a href='{png}'><img src='{png}' width='220'></a></td>"
            f"<td><code>{html.escape(cmd)}</code></td></tr>"
        )
    return (
        f"<h2>Three-stack attribution</h2><p>{rerun} of {s['scenarios']} scenarios were candidates (a failure, "
        f"or proxy &gt;= {attr.CANDIDATE:g}) and ran again on the reference stacks; {cl[attr.NOT_CANDIDATE]} were "
        f"not re-run. <b>flaw</b>: only the stack under test fails; <b>model</b>: the unflawed U-Net fails too; "
        f"<b>stack</b>: ground truth fails too (docs/agent.md).</p><table><tr>{head}</tr><tr>{cells}</tr></table>"
        + (
            "<table><tr><th>class</th><th>failure mode</th><th>job</th><th>under test</th><th>references</th>"
            "<th>the three paths</th>"
            f"<th>replay</th></tr>{''.join(items)}</table>"
            if items
            else ""
        )
    )


def _found_html(store, store_path: str, campaign: str, out_dir: str, top: int) -> str:
    """What the campaign searched for, first (issue #78): its findings, their distinct places at
    each reported radius and by what they hit, the rules they have in common (asg_analysis.rules,
    learnt from this campaign; checked only on fresh samples), and the first finding of each
    distinct place, largest reward first, with its top-down figure and replay command."""
    from asg_agent.campaign.findings import distinct_summary, finding_rule, findings
    from asg_analysis import rules
    from asg_analysis.exports import experiment_of, read_rows, target_of
    from asg_analysis.figures import top_down

    settings = json.loads(store.campaign(campaign)["settings"] or "{}")
    rule = finding_rule(settings)
    d = distinct_summary(findings(store, campaign))
    primary = d["primary_radius_m"]
    radii = ", ".join(f"<b>{v}</b> at {r:g} m" if r == primary else f"{v} at {r:g} m" for r, v in d["distinct"].items())
    hit = ", ".join(f"{html.escape(k)} {v}" for k, v in d["by_class"].items()) or "none"
    out = (
        f"<h2>What it found</h2><p><b>{d['findings']}</b> findings of the {html.escape(rule.name)} reward "
        f"(reward &gt;= {rule.finding_at:g}); distinct: {radii} (a finding is distinct when the obstacle it hit, "
        f"or where it ended without contact, lies at least {primary:g} m from every earlier distinct one of its "
        f"class). By what they hit: {hit}.</p>"
    )
    try:
        rows, camp = read_rows([], store_path, campaign)
        learnt = rules.learn(rows, experiment_of(camp), target_of(camp))
        out += "<h3>Rules</h3><pre>" + html.escape("\n".join(rules.lines(learnt))) + "</pre>"
    except ValueError as e:
        out += f"<h3>Rules</h3><p>none: {html.escape(str(e))}</p>"
    best = sorted(d["first_at_each_place"], key=lambda f: (-f["reward"], f["job"]))[:top]
    items = []
    for f in best:
        png = f"found_job{f['job']}.png"
        top_down(store, campaign, f["job"], os.path.join(out_dir, png))
        cls, x, y = f["place"]
        cmd = f"rosrun asg_agent replay {store_path} {campaign} {f['job']}"
        items.append(
            f"<tr><td>{f['job']}</td><td>{html.escape(f['termination'])}</td><td>{html.escape(cls)} at "
            f"({x:.1f}, {y:.1f}) m</td><td>{html.escape(str(f['attribution'] or ''))}</td><td>{f['reward']:.3f}</td>"
            f"<td><a href='{png}'><img src='{png}' width='220'></a></td><td><code>{html.escape(cmd)}</code></td></tr>"
        )
    if items:
        out += (
            f"<h3>The best distinct findings</h3><table><tr><th>job</th><th>termination</th><th>place</th>"
            f"<th>class</th><th>reward</th><th>top-down</th><th>replay</th></tr>{''.join(items)}</table>"
        )
    return out


def _stack_words(settings: dict) -> str:
    """The stack under test as the report names it: the paper's (perception / model) or another."""
    stack = settings.get("stack", "paper")
    if stack != "paper":
        return f"{stack} (command interface {settings.get('command_interface', 'vehicle_command')})"
    return f"{settings.get('perception')} / {settings.get('model')}"


def campaign_report(store_path: str, campaign: str, out_dir: str, top: int = 10) -> str:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from asg_analysis.figures import top_down
    from asg_agent.records.store import Store

    store = Store(store_path, create=False)
    c = store.campaign(campaign)
    if c is None:
        raise ValueError(f"no campaign {campaign!r} in {store_path}")
    s = store.summary(campaign, top=top)
    rows = list(
        store.db.execute("SELECT job, proxy, termination FROM scenarios WHERE campaign = ? ORDER BY job", (campaign,))
    )
    os.makedirs(out_dir, exist_ok=True)
    proxy = np.array([r[1] if r[1] is not None else np.nan for r in rows])
    fig, axes = plt.subplots(1, 2, figsize=(10, 3.4))
    axes[0].plot(proxy, ".", ms=3, color="0.4", label="proxy")
    axes[0].plot(np.fmax.accumulate(np.nan_to_num(proxy, nan=-np.inf)), "-", color="tab:red", label="best so far")
    window = 50
    if len(proxy) >= window:
        axes[0].plot(
            np.arange(window - 1, len(proxy)),
            np.convolve(np.nan_to_num(proxy), np.ones(window) / window, "valid"),
            color="tab:blue",
            label=f"mean of {window}",
        )
    axes[0].axhline(3, color="0.7", ls=":")
    axes[0].set_xlabel("scenario (job)")
    axes[0].set_ylabel("proxy")
    axes[0].legend(fontsize=8)
    axes[1].plot(np.cumsum(np.nan_to_num(proxy) >= FINDING), label=f">= {FINDING:g}")
    axes[1].plot(np.cumsum(np.nan_to_num(proxy) >= FINDING_STRONG), label=f">= {FINDING_STRONG:g}")
    axes[1].set_xlabel("scenarios spent")
    axes[1].set_ylabel("count found")
    axes[1].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(out_dir, "curves.png"), dpi=100)
    plt.close(fig)
    n = max(1, s["scenarios"])
    items = []
    for r in s["top"]:
        png = f"job{r['job']}.png"
        top_down(store, campaign, r["job"], os.path.join(out_dir, png))
        cmd = f"rosrun asg_agent replay {store_path} {campaign} {r['job']}"
        items.append(
            f"<tr><td>{r['job']}</td><td>{r['id']}</td><td>{r['episode']}.{r['step']}</td>"
            f"<td><b>{r['proxy']:.3f}</b></td><td>{r['vis']:+.2f}</td><td>{r['yaw_term']:.3f}</td>"
            f"<td>{r['plr']:.3f}</td><td>{html.escape(r['termination'])}</td>"
            f"<td><a href='{png}'><img src='{png}' width='220'></a></td><td><code>{html.escape(cmd)}</code></td></tr>"
        )
    terms = "".join(f"<tr><td>{html.escape(k)}</td><td>{v}</td></tr>" for k, v in sorted(s["terminations"].items()))
    settings = json.loads(c["settings"])
    best = "n/a" if s["max_proxy"] is None else f"{s['max_proxy']:.3f}"
    attribution = ""
    if s["attributed"]:
        attribution = (
            f"<h2>Attribution</h2><p>{s['attributed']} scenarios also ran on the reference stack "
            f"({reference_words(settings)}). Of the {s['proxy_ge_3']} with proxy "
            f"&gt;= 3, <b>{s['perception_ge3']}</b> are the perception's (reference proxy &lt; 2) and "
            f"<b>{s['stack_ge3']}</b> the stack's own (reference &gt;= 3); proxy &minus; reference "
            f"&gt;= 1 on {s['differential_ge1']}. Reward: {html.escape(str(settings.get('reward', 'proxy')))}. "
            f"Collisions (the paper's proxy does not score them): <b>{s['perception_collisions']}</b> "
            f"the perception's (the reference stack drove through the same scene), "
            f"<b>{s['stack_collisions']}</b> the stack's (the reference collided too).</p>"
        )
    attribution += _three_stack_html(store, store_path, campaign, s, out_dir, top)
    found = _found_html(store, store_path, campaign, out_dir, top)
    baseline = _baseline_html(c["experiment"], settings)
    page = f"""<!doctype html><html><head><meta charset="utf-8"><title>{html.escape(campaign)}</title>
<style>body{{font-family:sans-serif;margin:2em}}table{{border-collapse:collapse}}td,th{{border:1px solid #ccc;
padding:4px 8px;text-align:right}}code{{font-size:85%}}</style></head><body>
<h1>Campaign {html.escape(campaign)}</h1>
<p>method <b>{html.escape(c['method'])}</b>, experiment <b>{html.escape(c['experiment'])}</b>, seed {c['seed']},
stack: {html.escape(_stack_words(settings))},
workers {html.escape(', '.join(settings.get('workers', [])))}; store <code>{html.escape(store_path)}</code></p>
{found}
<h2>Counts (as in the paper's Table 2)</h2>
<table><tr><th>scenarios</th><th>proxy &gt;= 3</th><th>proxy &gt;= 4</th><th>per 1,000: &gt;= 3 / &gt;= 4</th><th>largest proxy</th></tr>
<tr><td>{s['scenarios']}</td><td>{s['proxy_ge_3']}</td><td>{s['proxy_ge_4']}</td>
<td>{1000 * s['proxy_ge_3'] / n:.0f} / {1000 * s['proxy_ge_4'] / n:.0f}</td><td>{best}</td></tr></table>
{attribution}{baseline}
<h2>Proxy over the campaign</h2><img src="curves.png" width="900">
<h2>Terminations</h2><table>{terms}</table>
<h2>Top {len(items)}</h2>
<table><tr><th>job</th><th>store id</th><th>episode.step</th><th>proxy</th><th>vis</th><th>yaw term</th><th>PLR</th>
<th>termination</th><th>top-down</th><th>replay</th></tr>{''.join(items)}</table>
</body></html>"""
    path = os.path.join(out_dir, "index.html")
    with open(path, "w", encoding="utf-8") as f:
        f.write(page)
    return path


def run(argv=None):
    p = argparse.ArgumentParser(prog=PROG, description=__doc__.split("\n\n")[0])
    sub = p.add_subparsers(dest="cmd", required=True)
    b = sub.add_parser("campaign")
    b.add_argument("store")
    b.add_argument("campaign")
    b.add_argument("out_dir")
    b.add_argument("--top", type=int, default=10)
    args = p.parse_args(argv)
    try:
        print(campaign_report(args.store, args.campaign, args.out_dir, args.top))
    except (ValueError, OSError, StoreError) as e:
        print(f"report: {e}", file=sys.stderr)
        return 2
    return 0
