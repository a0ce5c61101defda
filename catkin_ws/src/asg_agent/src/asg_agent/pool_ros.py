"""WorkerPool: the rospy adapter between a campaign and scene workers (docs/agent.md).

One actionlib client per worker namespace (`/worker_0` .. on this host or any host of the same
ROS master). A free worker gets the next proposal; results come back in any order. A worker that
does not answer within `answer_timeout` (wall seconds) is reported: its goal is cancelled, its
job comes back to the campaign as an ERROR (which re-queues it on another worker) and any late
answer of that goal is ignored, so no scenario is counted twice. A worker whose action server
is gone is left out until it comes back.
"""
import math
import queue
import threading
import time
from typing import Dict, List

import actionlib
import numpy as np
import rospy
from actionlib_msgs.msg import GoalStatus
from asg_msgs.msg import RunScenarioAction

from asg_scenario.convert import to_goal_msg

from .campaign import Outcome, Pool


def result_to_outcome(job: int, worker: str, result, wall: float) -> Outcome:
    n = len(result.trajectory)
    traj = np.zeros((n, 5), np.float32)
    for k, s in enumerate(result.trajectory):
        q = s.pose.orientation
        yaw = math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))
        traj[k] = (s.t, s.pose.position.x, s.pose.position.y, yaw, s.twist.angular.z)
    return Outcome(job=job, worker=worker, termination=result.termination_name or "ERROR", error=result.error,
                   sim_time=result.sim_time, num_control_msgs=result.num_control_msgs, trajectory=traj,
                   visibility=[float(v) for v in result.obstacle_visibility],
                   removed=[[r.layout_index, r.instance_index, r.reason] for r in result.removed_obstacles],
                   collision_with=result.collision_with, wall_time=wall)


class WorkerPool(Pool):
    def __init__(self, namespaces: List[str], answer_timeout: float = 300.0, connect_timeout: float = 120.0):
        self.answer_timeout = answer_timeout
        self.clients: Dict[str, actionlib.SimpleActionClient] = {}
        self.busy: Dict[str, tuple] = {}  # worker -> (job, goal handle token, start time)
        self.down: Dict[str, float] = {}  # worker -> when it went missing
        self.results: "queue.Queue[Outcome]" = queue.Queue()
        self.lock = threading.Lock()
        self.token = 0
        for ns in namespaces:
            ns = "/" + ns.strip("/")
            self.clients[ns] = actionlib.SimpleActionClient(ns + "/run_scenario", RunScenarioAction)
        deadline = time.time() + connect_timeout
        for ns, c in self.clients.items():
            left = max(0.1, deadline - time.time())
            if not c.wait_for_server(rospy.Duration(left)):
                raise RuntimeError(f"no scene worker answers at {ns}/run_scenario after {connect_timeout:.0f} s "
                                   f"(is `roslaunch launch/worker.launch ns:={ns.strip('/')}` running?)")
        rospy.loginfo("pool: %d worker(s): %s", len(self.clients), ", ".join(self.clients))

    @property
    def workers(self):
        return list(self.clients)

    def free(self):
        now = time.time()
        out = []
        with self.lock:
            for ns, c in self.clients.items():
                if ns in self.busy:
                    continue
                if ns in self.down:
                    if now - self.down[ns] < 5.0 or not c.wait_for_server(rospy.Duration(0.01)):
                        continue
                    rospy.logwarn("pool: %s is back", ns)
                    del self.down[ns]
                out.append(ns)
        return out

    def submit(self, worker, job, request):
        with self.lock:
            self.token += 1
            token = self.token
            self.busy[worker] = (job, token, time.time())
        t0 = time.time()

        def done(state, result):
            with self.lock:
                current = self.busy.get(worker)
                if current is None or current[1] != token:
                    return  # an answer we stopped waiting for
                del self.busy[worker]
            wall = time.time() - t0
            if result is None or state not in (GoalStatus.SUCCEEDED, GoalStatus.ABORTED):
                self.results.put(Outcome(job=job, worker=worker, termination="ERROR", wall_time=wall,
                                         error=f"{worker}: goal ended {GoalStatus.to_string(state)} without a result"))
            else:
                self.results.put(result_to_outcome(job, worker, result, wall))

        self.clients[worker].send_goal(to_goal_msg(request), done_cb=done)

    def poll(self, timeout):
        out = []
        try:
            out.append(self.results.get(timeout=timeout))
            while True:
                out.append(self.results.get_nowait())
        except queue.Empty:
            pass
        now = time.time()
        with self.lock:
            for ns, (job, token, t0) in list(self.busy.items()):
                if now - t0 > self.answer_timeout:
                    del self.busy[ns]
                    self.down[ns] = now
                    self.clients[ns].cancel_all_goals()
                    rospy.logerr("pool: %s did not answer job %d within %.0f s: re-queued", ns, job, self.answer_timeout)
                    out.append(Outcome(job=job, worker=ns, termination="ERROR", wall_time=now - t0,
                                       error=f"{ns} did not answer within {self.answer_timeout:.0f} s"))
        return out
