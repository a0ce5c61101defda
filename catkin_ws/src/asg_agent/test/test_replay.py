"""Sum tree and prioritized replay: sums, sampling frequencies, importance weights, persistence."""
import numpy as np
import pytest

from asg_agent.replay import PrioritizedReplay, SumTree


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
