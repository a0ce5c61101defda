"""The stack node's side of the lockstep protocol (issue #26): repeated announcements, frames of
an earlier run, frames after the node failed the run."""

from asg_lockstep import StackProtocol
from asg_lockstep.stack_protocol import ACK_DEFERRALS, Run

S = 10**9
WINDOW = 100000 * S


def test_repeated_announcements_are_one_run_and_a_new_run_forgets_the_failure():
    p = StackProtocol(WINDOW)
    assert p.announce(Run(7, 3, 4 * WINDOW))
    assert not p.announce(Run(7, 3, 4 * WINDOW))  # the worker repeats it until every node acked
    assert p.runs == 1
    p.fail("camera frames are 320x240")
    assert not p.accept(4 * WINDOW + S)  # failed: nothing more of this run
    assert p.announce(Run(7, 4, 5 * WINDOW))  # the same scenario again: a new run
    assert p.failed is None and p.runs == 2
    assert p.accept(5 * WINDOW + S)


def test_frames_outside_the_current_window_are_dropped_and_counted():
    p = StackProtocol(WINDOW)
    assert not p.accept(S)  # before any run
    p.announce(Run(1, 1, 2 * WINDOW))
    assert not p.accept(2 * WINDOW - 1)  # the run before's last frame, late
    assert p.accept(2 * WINDOW)
    assert p.accept(3 * WINDOW - 1)
    assert not p.accept(3 * WINDOW)  # just past the window
    assert p.stale == 3
    assert abs(p.seconds(2 * WINDOW + 1500 * 10**6) - 1.5) < 1e-12


def test_ticks_of_another_scenario_or_run_are_not_answered():
    p = StackProtocol(WINDOW)
    assert not p.tick(1, 2 * WINDOW)  # before any run
    p.announce(Run(1, 1, 2 * WINDOW))
    assert p.tick(1, 2 * WINDOW + S)
    assert not p.tick(2, 2 * WINDOW + S)  # another scenario's
    assert not p.tick(1, WINDOW + S)  # the run before's, late
    assert p.stale == 1


def test_acknowledge_defers_for_missing_inputs_then_gives_up_for_good():
    p = StackProtocol(WINDOW)
    assert p.acknowledge(True) and p.deferred == 0
    assert [p.acknowledge(False) for _ in range(ACK_DEFERRALS)] == [False] * ACK_DEFERRALS
    assert p.acknowledge(False) and p.gave_up  # the 7th announcement: acknowledged anyway
    assert p.acknowledge(False)  # and never waits again
    q = StackProtocol(WINDOW)
    assert not q.acknowledge(False) and q.acknowledge(True) and q.deferred == 0  # connected: counting restarts
    assert not q.acknowledge(False)


def test_the_deferral_count_is_the_cpp_twins():
    import os
    import re

    header = os.path.join(
        os.path.dirname(os.path.abspath(__file__)), "..", "include", "asg_lockstep", "stack_protocol.hpp"
    )
    m = re.search(r"constexpr int kAckDeferrals = (\d+);", open(header, encoding="utf-8").read())
    assert m and int(m.group(1)) == ACK_DEFERRALS
