"""asg_analysis.studies.learned (issue #67): each obstacle attribute's share among proposed layouts, flaw
findings and the obstacles they hit, early and late in the budget."""

import numpy as np

from asg_analysis.studies import learned

MESHES = ["juniper"] * 4 + ["barberry"] * 4


def _row(job, on_route, flaw):
    # Exp. 1's route runs from (20, 20) to (80, 80): a point (50 + s, 50 - s) is s * sqrt(2) m beside it
    far = [(5.0 + 10 * k, 95.0) for k in range(8)]
    pos = list(far)
    if on_route:
        pos[0] = (53.0, 53.0)  # a juniper on the route, past halfway
    return {
        "job": job,
        "positions": pos,
        "meshes": MESHES,
        "attribution": "flaw" if flaw else "not_candidate",
        "collision_with": 0 if flaw else None,
    }


def test_a_search_that_moves_to_what_its_findings_hold_shows_it_late():
    camp = {"experiment": "exp1"}
    rows = [_row(j, on_route=(j >= 10 and j % 2 == 0), flaw=(j >= 10 and j % 2 == 0)) for j in range(20)]
    res = learned.shares([(camp, rows)], budget=20)
    s = res["shares"]["class, beside"]["juniper, 0-2 m"]
    assert s["proposed_early"] == 0.0 and s["proposed_late"] == 5 / 80
    assert s["findings_late"] == 1 / 8 and s["findings_early"] is None
    assert s["hit_late"] == 1.0
    assert res["n"] == {
        "proposed_early": 80,
        "proposed_late": 80,
        "findings_early": 0,
        "findings_late": 40,
        "hit_early": 0,
        "hit_late": 5,
    }
    assert res["shares"]["along"]["Q3"]["hit_late"] == 1.0  # t = 0.55: the third quarter
    md = learned.markdown(res)
    assert "| class, beside | juniper, 0-2 m | 0 % | 6 % | - | 12 % | - | 100 % |" in md
    # bands in reading order, not alphabetical
    bands = [ln.split("|")[2].strip() for ln in md.splitlines() if ln.startswith("| beside |")]
    assert bands == sorted(bands, key=lambda b: float(b.split("-")[0].replace(">= ", "").split()[0]))
    assert np.isclose(sum(v["proposed_late"] for v in res["shares"]["beside"].values()), 1.0)


def test_an_obstacle_in_anothers_shadow_is_shaded():
    # Exp. 1's sun: yaw 150 deg, 35 deg up: a juniper's (4.5 m) shadow runs 6.4 m away from the sun
    camp = {"experiment": "exp1"}
    pos = [(5.0 + 10 * k, 95.0) for k in range(8)]
    pos[0], pos[4] = (50.0, 30.0), (50.0 + 3.0 * np.cos(np.radians(330)), 30.0 + 3.0 * np.sin(np.radians(330)))
    attrs = learned.obstacle_attributes(camp, {"positions": pos, "meshes": MESHES})
    assert attrs[4]["shaded"] == "shaded" and attrs[0]["shaded"] == "lit" and attrs[1]["shaded"] == "lit"


def test_the_figure_draws_the_shares(tmp_path):
    camp = {"experiment": "exp1"}
    rows = [_row(j, on_route=(j >= 10 and j % 2 == 0), flaw=(j >= 10 and j % 2 == 0)) for j in range(20)]
    res = learned.shares([(camp, rows)], budget=20)
    out = tmp_path / "learned.png"
    drawn = learned.figure(res, str(out))
    assert out.stat().st_size > 10_000
    values = list(res["shares"]["class, beside"])
    k = values.index("juniper, 0-2 m")
    bars = [g for g, _ in learned.FIGURE_BARS]
    assert drawn["class, beside"][bars.index("proposed_late")][k] == 100 * 5 / 80
    assert drawn["class, beside"][bars.index("hit_late")][k] == 100.0
    assert set(drawn) == {"class, beside", "along", "shaded"}


def test_early_can_end_where_a_search_stops_sampling_uniformly():
    # --split: early is the jobs below the split, not half the budget
    camp = {"experiment": "exp1"}
    rows = [_row(j, on_route=j >= 4, flaw=j >= 4) for j in range(20)]
    half = learned.shares([(camp, rows)], budget=20)
    split = learned.shares([(camp, rows)], budget=20, split=4)
    s = split["shares"]["class, beside"]["juniper, 0-2 m"]
    assert s["proposed_early"] == 0.0 and s["proposed_late"] == 16 / 128
    assert half["shares"]["class, beside"]["juniper, 0-2 m"]["proposed_early"] == 6 / 80
    assert split["n"]["proposed_early"] == 32 and "jobs below 4 of the budget of 20" in learned.markdown(split)
    assert "jobs below half the budget of 20" in learned.markdown(half)
    import pytest

    with pytest.raises(ValueError, match="split 20"):
        learned.shares([(camp, rows)], budget=20, split=20)
