"""The lockstep input gate (asg_lockstep.gate): what a tick waits for and the order of delivery."""

import pytest

from asg_lockstep.gate import TickGate, kind_of

W = 4096 * 10**9
B = 8192 * 10**9
MS = 10**6


def gate():
    g = TickGate(W)
    g.add("goal", "run")
    g.add("points", "camera")
    g.add("odom", "state")
    g.begin(B)
    return g


def test_kinds_of_standard_types_and_a_clear_error_otherwise():
    assert kind_of("nav_msgs/Odometry") == "state"
    assert kind_of("sensor_msgs/PointCloud2") == "camera"
    assert kind_of("std_msgs/String", "run") == "run"
    with pytest.raises(ValueError, match="std_msgs/String.*kind="):
        kind_of("std_msgs/String")
    with pytest.raises(ValueError, match="'later'"):
        kind_of("nav_msgs/Odometry", "later")


def test_tick_waits_for_every_input_then_delivers_in_stamp_order():
    g = gate()
    # Out of order across topics, as separate callback threads deliver them.
    g.offer("odom", B + 50 * MS, "odom@50")
    g.offer("points", B + 0, "points@0")
    g.offer("odom", B + 0, "odom@0")
    assert g.tick(B + 50 * MS, B + 0, 1)
    assert g.missing() == ["goal"]  # the goal of the run has not arrived
    g.offer("goal", B, "goal")
    assert g.missing() == []
    # Same stamp: topic order as added (goal, points, odom); then later stamps.
    assert g.release() == [("goal", "goal"), ("points", "points@0"), ("odom", "odom@0"), ("odom", "odom@50")]
    assert g.release() == []


def test_camera_frame_of_the_tick_must_be_here():
    g = gate()
    g.offer("goal", B, "goal")
    g.offer("odom", B + 100 * MS, "odom@100")
    g.tick(B + 100 * MS, B + 66 * MS, 2)
    assert g.missing() == ["points"]
    g.offer("points", B + 0, "points@0")
    assert g.missing() == ["points"]  # an older frame is not the one published before the tick
    g.offer("points", B + 66 * MS, "points@66")
    assert g.missing() == []
    assert [m for _, m in g.release()] == ["goal", "points@0", "points@66", "odom@100"]


def test_messages_after_the_tick_stay_held_for_the_next():
    g = gate()
    g.offer("goal", B, "goal")
    g.offer("odom", B + 50 * MS, "odom@50")
    g.offer("odom", B + 100 * MS, "odom@100")  # arrived early: belongs to the next tick
    g.tick(B + 50 * MS, 0, 0)
    assert [m for _, m in g.release()] == ["goal", "odom@50"]
    g.tick(B + 100 * MS, 0, 0)
    assert [m for _, m in g.release()] == ["odom@100"]


def test_a_late_frame_of_an_earlier_run_is_dropped_and_counted():
    g = gate()
    g.offer("odom", B - 1, "old")
    assert g.stale == 1
    assert not g.tick(B - 1, 0, 0)
    g.offer("odom", B + 10 * MS, "held")
    g.begin(B + W)  # the next run: what was held is dropped too
    assert g.stale == 3
    g.tick(B + W, 0, 0)
    assert g.missing() == ["goal", "odom"]


def test_the_goal_published_before_its_run_is_announced_is_kept():
    g = gate()
    g.offer("goal", B + W, "goal of the next run")  # the worker publishes it before announcing
    g.offer("odom", B + 10 * MS, "odom of this run")
    g.tick(B + 10 * MS, 0, 0)
    assert g.missing() == ["goal"]  # not this run's goal
    assert [m for _, m in g.release()] == ["odom of this run"]
    g.begin(B + W)
    g.offer("odom", B + W, "odom@0")
    g.tick(B + W, 0, 0)
    assert g.missing() == []
    assert [m for _, m in g.release()] == ["goal of the next run", "odom@0"]
    with pytest.raises(KeyError, match="cmd_vel"):
        g.offer("cmd_vel", B + W, None)
