"""WorkerPool: the rospy adapter between a campaign and scene workers (docs/agent.md).

One actionlib client per worker namespace (`/worker_0` .. on this host or any host of the same
ROS master). A free worker gets the next proposal; results come back in any order. A worker that
does not answer within `answer_timeout` (wall seconds) is reported: its goal is cancelled, its
job comes back to the campaign as an ERROR (which re-queues it on another worker) and any late
answer of that goal is ignored, so no scenario is counted twice. A worker whose action server
is gone is left out until it comes back.
"""

import queue
import threading
import time
from typing import Dict, List

import actionlib
import numpy as np
import rospy
from actionlib_msgs.msg import GoalStatus
from asg_scenario.report import yaw_of
from actionlib.action_client import CommState
from asg_msgs.msg import RunScenarioAction

from asg_scenario.convert import to_goal_msg

from asg_agent.campaign.dispatch import Outcome, Pool

STATUS = {
    GoalStatus.PENDING: "PENDING",
    GoalStatus.ACTIVE: "ACTIVE",
    GoalStatus.PREEMPTED: "PREEMPTED",
    GoalStatus.SUCCEEDED: "SUCCEEDED",
    GoalStatus.ABORTED: "ABORTED",
    GoalStatus.REJECTED: "REJECTED",
    GoalStatus.PREEMPTING: "PREEMPTING",
    GoalStatus.RECALLING: "RECALLING",
    GoalStatus.RECALLED: "RECALLED",
    GoalStatus.LOST: "LOST",
}


def result_to_outcome(job: int, worker: str, result, wall: float) -> Outcome:
    n = len(result.trajectory)
    traj = np.zeros((n, 5), np.float32)
    for k, s in enumerate(result.trajectory):
        q = s.pose.orientation
        yaw = yaw_of(q.x, q.y, q.z, q.w)
        traj[k] = (s.t, s.pose.position.x, s.pose.position.y, yaw, s.twist.angular.z)
    return Outcome(
        job=job,
        worker=worker,
        termination=result.termination_name or "ERROR",
        error=result.error,
        sim_time=result.sim_time,
        num_control_msgs=result.num_control_msgs,
        trajectory=traj,
        visibility=[float(v) for v in result.obstacle_visibility],
        removed=[[r.layout_index, r.instance_index, r.reason] for r in result.removed_obstacles],
        collision_with=result.collision_with,
        wall_time=wall,
    )


class WorkerPool(Pool):
    def __init__(
        self,
        namespaces: List[str],
        answer_timeout: float = 300.0,
        connect_timeout: float = 120.0,
        accept_timeout: float = 20.0,
    ):
        self.answer_timeout = answer_timeout
        # A goal the worker's action server has not acknowledged this long after it went out was
        # dropped (sent to a scene worker that had just respawned): re-queued without waiting for
        # answer_timeout. The 2-hour soak lost 3 x 300 s of a worker that way.
        self.accept_timeout = accept_timeout
        # The plain ActionClient: one handle per goal, so a late status of an earlier goal can never
        # be taken for the current one (SimpleActionClient tracks a single goal per client).
        self.clients: Dict[str, actionlib.ActionClient] = {}
        self.busy: Dict[str, tuple] = {}  # worker -> (job, goal handle, start time)
        self.handles = []  # keeps goal handles alive until they are done
        self.down: Dict[str, float] = {}  # worker -> when it went missing
        self.results: "queue.Queue[Outcome]" = queue.Queue()
        self.lock = threading.RLock()
        self.node_uri: Dict[str, str] = {}  # worker -> URI of its scene_worker node when its job went out
        self.next_liveness = 0.0
        for ns in namespaces:
            ns = "/" + ns.strip("/")
            self.clients[ns] = actionlib.ActionClient(ns + "/run_scenario", RunScenarioAction)
        deadline = time.time() + connect_timeout
        for ns, c in self.clients.items():
            left = max(0.1, deadline - time.time())
            if not c.wait_for_server(rospy.Duration(left)):
                raise RuntimeError(
                    f"no scene worker answers at {ns}/run_scenario after {connect_timeout:.0f} s "
                    f"(is `roslaunch launch/worker.launch ns:={ns.strip('/')}` running?)"
                )
        rospy.loginfo("pool: %d worker(s): %s", len(self.clients), ", ".join(self.clients))

    @property
    def workers(self):
        return list(self.clients)

    def free(self):
        now = time.time()
        with self.lock:
            idle = [ns for ns in self.clients if ns not in self.busy]
            down = dict(self.down)
        out = []
        for ns in idle:
            if ns in down:  # checked outside self.lock (see transition)
                if now - down[ns] < 5.0 or not self.clients[ns].wait_for_server(rospy.Duration(0.01)):
                    continue
                rospy.logwarn("pool: %s is back", ns)
                with self.lock:
                    self.down.pop(ns, None)
            out.append(ns)
        return out

    def submit(self, worker, job, request):
        t0 = time.time()
        state = {"handle": None, "done": False}  # this submission, whatever its goal handle

        def transition(gh):
            # Called from actionlib's threads while they hold actionlib's own lock: never call
            # into actionlib with self.lock held (submit does not), or the two would deadlock.
            if gh.get_comm_state() != CommState.DONE:
                return
            with self.lock:
                if state["done"]:
                    return
                state["done"] = True
                if gh in self.handles:
                    self.handles.remove(gh)
                current = self.busy.get(worker)
                if current is None or current[1] is not state:
                    return  # an answer we stopped waiting for (timed out and re-queued)
                del self.busy[worker]
            wall = time.time() - t0
            status, result = gh.get_goal_status(), gh.get_result()
            if result is None or status not in (GoalStatus.SUCCEEDED, GoalStatus.ABORTED):
                with self.lock:  # the server went away (LOST): let it come back before the next goal
                    self.down[worker] = time.time()
                self.results.put(
                    Outcome(
                        job=job,
                        worker=worker,
                        termination="ERROR",
                        wall_time=wall,
                        error=f"{worker}: goal ended {STATUS.get(status, status)} without a result",
                    )
                )
            else:
                self.results.put(result_to_outcome(job, worker, result, wall))

        uri = self._scene_worker_uri(worker)
        with self.lock:
            self.busy[worker] = (job, state, t0)
            self.node_uri[worker] = uri
        gh = self.clients[worker].send_goal(to_goal_msg(request), transition_cb=transition)
        with self.lock:
            state["handle"] = gh
            if not state["done"]:
                self.handles.append(gh)

    @staticmethod
    def _scene_worker_uri(worker):
        """The master's record of the worker's scene_worker node ("" if it has none)."""
        try:
            import rosgraph

            return rosgraph.Master(rospy.get_name()).lookupNode(worker.rstrip("/") + "/scene_worker")
        except Exception:  # noqa: BLE001 - unregistered (dead) or the master unreachable
            return ""

    def _dead_workers(self, now):
        """Busy workers whose scene_worker process died (unregistered, or a respawn with a new URI)
        since their job went out: their run is lost. Checked every 2 s, one master call each."""
        if now < self.next_liveness:
            return []
        self.next_liveness = now + 2.0
        with self.lock:
            watched = {ns: self.node_uri.get(ns, "") for ns in self.busy}
        return [ns for ns, uri in watched.items() if uri and self._scene_worker_uri(ns) != uri]

    def poll(self, timeout):
        out = []
        try:
            out.append(self.results.get(timeout=timeout))
            while True:
                out.append(self.results.get_nowait())
        except queue.Empty:
            pass
        now = time.time()
        dead = set(self._dead_workers(now))
        with self.lock:
            waiting = [
                (ns, state)
                for ns, (job, state, t0) in self.busy.items()
                if now - t0 > self.accept_timeout and state["handle"] is not None
            ]
        # Outside self.lock (see transition): goals the server never acknowledged.
        unacked = {ns for ns, state in waiting if state["handle"].get_comm_state() == CommState.WAITING_FOR_GOAL_ACK}
        with self.lock:
            stale = []
            for ns, (job, state, t0) in list(self.busy.items()):
                if ns in dead:
                    why = "the scene worker died during the run"
                elif ns in unacked:
                    why = f"never acknowledged the goal within {self.accept_timeout:.0f} s"
                elif now - t0 > self.answer_timeout:
                    why = f"did not answer within {self.answer_timeout:.0f} s"
                else:
                    continue
                del self.busy[ns]
                self.down[ns] = now
                stale.append(state["handle"])
                rospy.logerr("pool: %s, job %d: %s: re-queued", ns, job, why)
                out.append(Outcome(job=job, worker=ns, termination="ERROR", wall_time=now - t0, error=f"{ns}: {why}"))
        for gh in stale:  # outside self.lock (see transition)
            if gh is not None:
                gh.cancel()
        return out
