"""Sum tree and prioritized replay: sums, sampling frequencies, importance weights, persistence."""

import numpy as np
import pytest

from asg_agent.search.per_buffer import PrioritizedReplay, SumTree


def test_sum_tree_sums_and_find():
    t = SumTree(5)
    for i, p in enumerate([1.0, 2.0, 0.0, 3.0, 4.0]):
        t.set(i, p)
    assert t.total == 10.0
    assert [t.find(m) for m in (0.0, 0.99, 1.0, 2.99, 3.0, 5.99, 6.0, 9.99)] == [0, 0, 1, 1, 3, 3, 4, 4]
    t.set(3, 0.5)
    assert t.total == 7.5
    u = SumTree(5)
    u.set_all(np.array([1.0, 2.0, 0.0, 0.5, 4.0]))
    assert np.array_equal(u.tree, t.tree)
    with pytest.raises(ValueError):
        t.set(0, float("nan"))


def test_sampling_frequencies_follow_priorities():
    rng = np.random.default_rng(0)
    buf = PrioritizedReplay(4, 1, 1, alpha=1.0)
    for k in range(4):
        buf.add([k], [0], 0.0, [k], False)
    buf.update_priorities([0, 1, 2, 3], np.array([1.0, 2.0, 3.0, 4.0]) - buf.eps)
    counts = np.zeros(4)
    for _ in range(5000):
        counts += np.bincount(buf.sample(8, rng)["index"], minlength=4)
    freq = counts / counts.sum()
    assert np.allclose(freq, [0.1, 0.2, 0.3, 0.4], atol=0.01)


def test_alpha_flattens_priorities_and_importance_weights():
    rng = np.random.default_rng(1)
    buf = PrioritizedReplay(2, 1, 1, alpha=0.5, beta0=0.4, beta_steps=10)
    buf.add([0], [0], 0.0, [0], False)
    buf.add([1], [0], 0.0, [1], True)
    buf.update_priorities([0, 1], np.array([1.0, 9.0]) - buf.eps)
    assert np.isclose(buf.tree.get(0), 1.0) and np.isclose(buf.tree.get(1), 3.0)  # p^alpha
    b = buf.sample(2, rng)
    P = np.array([0.25, 0.75])
    w = (2 * P[b["index"]]) ** -0.4
    assert np.allclose(b["weight"].ravel(), w / ((2 * P) ** -0.4).max())
    assert b["not_done"][b["index"] == 1].tolist() in ([], [[0.0]], [[0.0], [0.0]])
    for _ in range(20):
        buf.sample(2, rng)
    assert buf.beta() == 1.0


def test_new_transitions_get_the_largest_priority_and_state_round_trips():
    buf = PrioritizedReplay(8, 2, 1)
    buf.add([0, 0], [0], 1.0, [0, 0], False)
    buf.update_priorities([0], [5.0])
    buf.add([1, 1], [0], 1.0, [1, 1], False)
    assert buf.tree.get(1) == buf.tree.get(0)
    other = PrioritizedReplay(8, 2, 1)
    other.load_state_dict(buf.state_dict())
    assert np.array_equal(other.tree.tree, buf.tree.tree) and len(other) == 2
    with pytest.raises(ValueError, match="capacity"):
        PrioritizedReplay(4, 2, 1).load_state_dict(buf.state_dict())


def test_new_transitions_get_the_largest_stored_priority_not_the_all_time_largest():
    # Issue #25: a priority that has since fallen (or been overwritten) must not set the level.
    buf = PrioritizedReplay(3, 1, 1, alpha=1.0)
    for k in range(3):
        buf.add([k], [0], 0.0, [k], False)
    buf.update_priorities([0, 1, 2], np.array([100.0, 2.0, 3.0]) - buf.eps)
    buf.update_priorities([0], [1.0 - buf.eps])  # the outlier's error has fallen
    buf.add([3], [0], 0.0, [3], False)  # overwrites slot 0
    assert buf.tree.get(0) == pytest.approx(3.0)  # the largest stored, not 100
    # Overwriting the largest itself: the new one gets the largest of what is still stored.
    buf.add([4], [0], 0.0, [4], False)  # overwrites slot 1 (2.0)
    assert buf.tree.get(1) == pytest.approx(3.0)


def test_sum_tree_never_returns_an_empty_slot_near_node_boundaries():
    # Issue #25: rounding in the inner sums let find() walk into an empty leaf of a buffer that is
    # not full (p = 0: an infinite importance weight, a NaN loss). Fuzz at and next to every
    # prefix-sum boundary, and at the top of the range.
    rng = np.random.default_rng(7)
    bad = 0
    for trial in range(300):
        cap = int(rng.integers(2, 70))
        count = int(rng.integers(1, cap + 1))
        t = SumTree(cap)
        for i in range(count):
            t.set(i, float(rng.choice([rng.uniform(1e-3, 1.0), rng.uniform(1e-9, 1e-6), 10 ** rng.uniform(-3, 3)])))
        prefix = np.cumsum(t.tree[t.size : t.size + count])
        masses = [t.total, np.nextafter(t.total, 0)]
        for b in prefix:
            masses += [b, np.nextafter(b, 0), np.nextafter(b, np.inf)]
        for m in masses:
            m = min(m, np.nextafter(t.total, 0))
            i = t.find(m)
            bad += not (0 <= i < count and t.get(i) > 0)
    assert bad == 0


def test_sampling_a_partly_filled_buffer_gives_finite_weights():
    rng = np.random.default_rng(3)
    buf = PrioritizedReplay(1000, 1, 1, alpha=0.6)
    for k in range(333):
        buf.add([k], [0], 0.0, [k], False)
    buf.update_priorities(np.arange(333), rng.lognormal(0, 3, 333))
    for _ in range(300):
        b = buf.sample(128, rng)
        assert np.all(b["index"] < 333) and np.all(np.isfinite(b["weight"])) and np.all(b["weight"] > 0)


def test_a_replay_brings_up_the_stack_the_campaign_ran(monkeypatch):
    # Issue #39: a depth-stack campaign's scenario replays on a depth-stack worker, and its
    # markers are recorded (they change nothing the stack decides).
    import subprocess

    from asg_agent.ros import replay

    launched = []
    monkeypatch.setattr(subprocess, "Popen", lambda cmd, **kw: launched.append(cmd))
    monkeypatch.setenv("ROS_MASTER_URI", "http://127.0.0.1:11311")  # bring_up_worker points it at its port
    stack = {"stack": "depth", "perception": "ground_truth", "model": "flawed", "planner_config": "planner.yaml"}
    replay.bring_up_worker(stack, 11499)
    cmd = launched[-1]
    assert "stack:=depth" in cmd and "markers:=true" in cmd and "odom_every_tick:=true" in cmd
    replay.bring_up_worker({**stack, "stack": "paper", "perception": "unet"}, 11499)
    assert "stack:=paper" in launched[-1] and "perception:=unet" in launched[-1]


def test_a_free_running_stack_is_rerun_not_judged():
    # issue #55: a stack registered `mode: free` has no client gating it; replay runs its scenario
    # again and says so instead of NOT REPRODUCED
    from asg_agent.ros.replay import free_running

    assert free_running({"registration": {"mode": "free", "sim_time": True}})
    assert not free_running({"registration": {"mode": "lockstep"}})
    assert not free_running({}) and not free_running(None)


def test_a_replays_own_master_never_joins_another_on_its_port():
    # two replays at once, or a replay beside a sim-time stack's replay, each bring up a master of
    # their own: a port something listens on is skipped, or refused when asked for by --port
    import socket

    from asg_agent.ros import replay

    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as held:
        held.bind(("127.0.0.1", 0))
        held.listen(1)
        busy = held.getsockname()[1]
        with pytest.raises(ValueError, match=f"--port {busy} is in use"):
            replay.private_port(busy)
        first = replay.private_port()
        assert first >= replay.FIRST_PORT and replay._free(first)
        with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as other:
            other.bind(("127.0.0.1", first))
            other.listen(1)
            assert replay.private_port() > first  # the next free one, not the one in use
