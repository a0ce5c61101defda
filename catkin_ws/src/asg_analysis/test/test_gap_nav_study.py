"""analysis.gap_nav_study: the warm-up rule, the grouping of failure layouts, the reruns (issue #68)."""

import gzip
import json

import numpy as np
import pytest

from asg_analysis.studies import gap_nav_study as g


def layout(*xy):
    return [list(p) for p in xy]


def test_init_random_is_make_methods_rule():
    assert [g.init_random(b) for b in (5, 10, 350, 1000, 5000)] == [1, 1, 35, 100, 100]


def test_layouts_link_when_every_obstacle_is_within_the_radius_and_groups_chain():
    a = layout((0, 0), (50, 50))
    b = layout((4, 0), (50, 54))  # 4 m from a, obstacle by obstacle
    c = layout((8, 0), (50, 58))  # 4 m from b, 8 m from a: single linkage chains it to a
    d = layout((40, 40), (50, 50))  # the second obstacle where a's stands, the first 57 m away
    assert g.layout_groups([a, b, c, d], 5.0) == [[0, 1, 2], [3]]
    assert g.layout_groups([a, b, c, d], 3.0) == [[0], [1], [2], [3]]
    assert g.layout_groups([a, b, c, d], 100.0) == [[0, 1, 2, 3]]
    assert g.layout_groups([a, b, c, d], 4.0) == [[0, 1, 2], [3]]  # at the radius: linked
    assert g.span([a, b, c, d], [0, 1, 2]) == pytest.approx(8.0)
    assert g.span([a], [0]) == 0.0


def test_an_obstacle_is_compared_with_the_same_obstacle_not_the_nearest():
    a = layout((10, 10), (30, 30))
    swapped = layout((30, 30), (10, 10))  # the same places, the obstacles swapped: 28 m apart each
    assert g.layout_groups([a, swapped], 5.0) == [[0], [1]]


def test_groups_come_largest_first_then_by_their_first_layout():
    far = [layout((10.0 * k, 0)) for k in range(4)]  # 10 m apart: four single groups
    near = far + [layout((30, 1)), layout((0, 1))]  # joins 3, then 0
    assert g.layout_groups(far, 5.0) == [[0], [1], [2], [3]]
    assert g.layout_groups(near, 5.0) == [[0, 5], [3, 4], [1], [2]]
    assert g.layout_groups(np.zeros((0, 8, 2)), 5.0) == []
    with pytest.raises(ValueError):
        g.layout_groups(np.zeros((3, 16)), 5.0)


def test_along_is_the_struck_obstacles_distance_along_the_route():
    start, goal = np.array([20.0, 20.0]), np.array([80.0, 80.0])
    row = {"positions": [[0, 0], [30, 30], [40, 20]], "collision_with": 1}
    assert g.along(row, start, goal) == pytest.approx(10 * np.sqrt(2))
    assert g.along(dict(row, collision_with=2), start, goal) == pytest.approx(10 * np.sqrt(2))
    assert g.struck_early([row, dict(row, collision_with=None)], start, goal) == 1


def test_reruns_counts_the_stored_failures_by_how_often_they_failed_again(tmp_path):
    per = [(True, 5), (True, 0), (True, 2), (True, 3), (False, 4)]
    spread = {
        "campaign": "c",
        "scenarios": 5,
        "repetitions": 5,
        "per_scenario": [{"stored": {"fails": f}, "fails_again": k} for f, k in per],
    }
    (tmp_path / "spread.json").write_text(json.dumps(spread))
    r = g.reruns(str(tmp_path / "spread.json"))
    assert r["fails_again"] == [0, 2, 3, 5] and r["stored_failures"] == 4
    assert (r["median"], r["at_most_2"], r["every_time"], r["never"], r["reruns_failing"]) == (2.5, 2, 1, 1, 10)


def export(path, name, outcomes, init_random=3, experiment="experiments/exp1-gap-nav-route.yaml"):
    settings = {"total": len(outcomes), "experiment_repo_file": experiment, "method_config": {}}
    if init_random is not None:
        settings["method_config"]["init_random"] = init_random
    head = {"name": name, "experiment_text": "scenario: ../scenarios/exp1.yaml\n", "settings": json.dumps(settings)}
    with gzip.open(path / f"{name}.jsonl.gz", "wt", encoding="utf-8") as f:
        f.write(json.dumps({"campaign": head}) + "\n")
        for job, hit in enumerate(outcomes):  # hit: the struck obstacle's distance along the route [m], or None
            p = [[20.0 + d / np.sqrt(2), 20.0 + d / np.sqrt(2)] for d in (hit if hit is not None else 50.0, 60.0)]
            row = {"job": job, "positions": p, "meshes": ["juniper", "barberry"], "proxy": 1.0}
            row.update(termination="COLLISION" if hit is not None else "SUCCESS", collision_with=0 if hit else None)
            f.write(json.dumps(row) + "\n")


def test_the_study_splits_the_search_from_its_warm_up(tmp_path):
    # budget 30: init_random 3. Warm-up: 1 failure in 3; searched: 9 of 27; uniform random: 1 of 30.
    export(tmp_path, "s", [5.0, None, None] + [15.0] * 9 + [None] * 18)
    export(tmp_path, "u", [40.0] + [None] * 29, init_random=None, experiment="experiments/exp1-gap-nav.yaml")
    s = g.study(str(tmp_path), ["s"], ["u"], spread=None)
    assert (s["warmup"]["failures"], s["warmup"]["scenarios"]) == (1, 3)
    assert (s["searched"]["failures"], s["searched"]["scenarios"]) == (9, 27)
    assert (s["uniform"]["failures"], s["uniform"]["scenarios"]) == (1, 30)
    q = s["ratio"]
    assert q["where_obstacles_may_stand"] == pytest.approx(10.0)
    assert q["search_over_warmup"] == pytest.approx(1.0)
    assert q["arm_over_uniform"] == pytest.approx(q["where_obstacles_may_stand"] * q["arm_over_warmup"])
    assert s["struck_first_25m"] == {
        "arm": 10,
        "arm_failures": 10,
        "warmup": 1,
        "warmup_failures": 1,
        "uniform": 0,
        "uniform_failures": 1,
    }
    top = s["seeds"]["s"]["largest_group"]
    assert (top["size"], top["next_size"], top["most_struck"], top["most_struck_failures"]) == (9, 1, "juniper 0", 9)
    assert g.BEGIN in g.markdown(s) and "| 3 | 1 | 333.3 (" in g.markdown(s)


def test_a_recorded_init_random_that_is_not_the_rule_is_an_error(tmp_path):
    export(tmp_path, "s", [None] * 30, init_random=5)
    export(tmp_path, "u", [None] * 30, init_random=None)
    with pytest.raises(ValueError, match="init_random 5"):
        g.study(str(tmp_path), ["s"], ["u"], spread=None)
