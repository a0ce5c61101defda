"""A stack node's side of the lockstep protocol (no rospy): which run is current, whether a frame
belongs to it, and whether this node has failed it. Stamps are integer nanoseconds; the ROS
adapter converts (`stamp.to_nsec()`)."""

from dataclasses import dataclass
from typing import Optional

#: [-] announcements (one each 0.5 s) a node may let pass unacknowledged while one of its inputs
#: has no peer yet (StackProtocol.acknowledge); the C++ twin's kAckDeferrals (stack_protocol.hpp)
#: is the same number (test_stack_protocol.py checks it).
ACK_DEFERRALS = 6


@dataclass
class Run:
    scenario_id: int
    run: int
    base: int  #: [ns] stamp of simulated time 0
    width: int = 0  #: [px] camera frames the worker will send
    height: int = 0


class StackProtocol:
    def __init__(self, window_ns: int):
        self.window = int(window_ns)
        self.run: Optional[Run] = None
        self.failed: Optional[str] = None  #: this node's reason for failing the current run
        self.runs = 0  #: runs seen
        self.stale = 0  #: frames dropped as not of the current run (whole node life)
        self.deferred = 0  #: announcements let pass in a row, waiting for inputs
        self.gave_up = False  #: acknowledges without waiting for inputs from now on

    def acknowledge(self, inputs_connected: bool) -> bool:
        """Whether to acknowledge the announcement now. A node that has just (re)started
        subscribes and advertises before the TCP links exist, and a message sent before then is
        lost (the run would end on the command timeout): it defers while `inputs_connected` is
        false, for at most ACK_DEFERRALS announcements (~3 s); then it acknowledges and never
        waits again, so that a stack lacking an input still runs."""
        if self.gave_up or inputs_connected:
            self.deferred = 0
            return True
        self.deferred += 1
        if self.deferred <= ACK_DEFERRALS:
            return False
        self.gave_up = True
        return True

    def announce(self, run: Run) -> bool:
        """The worker announced a run (repeatedly, until every node acknowledged). True when it
        is a new one: the node forgets the previous run and its failure."""
        if self.run is not None and self.run.run == run.run:
            return False
        self.run, self.failed = run, None
        self.runs += 1
        return True

    def current(self, stamp: int) -> bool:
        """Whether a message stamped `stamp` [ns] belongs to the current run's window."""
        r = self.run
        return r is not None and r.base <= stamp < r.base + self.window

    def accept(self, stamp: int) -> bool:
        """Whether to process a frame: of the current run (otherwise counted in `stale`), and the
        node has not failed the run."""
        if not self.current(stamp):
            self.stale += 1
            return False
        return self.failed is None

    def tick(self, scenario_id: int, stamp: int) -> bool:
        """Whether a control tick is of the current run (its scenario, in its window); a tick of
        the current scenario outside the window is counted in `stale`."""
        return self.run is not None and scenario_id == self.run.scenario_id and self.accept(stamp)

    def fail(self, reason: str) -> Run:
        """This node cannot go on with the current run; returns it (for the error message)."""
        self.failed = reason
        return self.run

    def seconds(self, stamp: int) -> float:
        """[s] simulated time of `stamp` in the current run."""
        return (stamp - self.run.base) * 1e-9
