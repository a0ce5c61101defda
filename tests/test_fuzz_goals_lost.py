"""Issue #79 item 6: the goal fuzzer (tests/fuzz_goals.py, run by bad_input.test and fuzz_inputs.py
goals) counted a goal the worker answered and the client never delivered as "answered, lost by the
client", not as a failure, so the client race of issue #68 could come back unseen. A lost answer
is now a failure. Shown here without ROS: a client that loses one answer of five."""

import types

import rospy

import fuzz_goals


class FakeClient:
    """Answers every goal ABORTED with an error text, except the third, which the worker answers
    (on the result topic) and the client never delivers."""

    results = None  # the harness's subscriber callback on the worker's result topic

    def __init__(self, *a, **k):
        self.sent, self.gh = 0, None

    def wait_for_server(self, timeout):
        return True

    def send_goal(self, goal):
        self.sent += 1
        gid = f"g{self.sent}"
        self.gh = types.SimpleNamespace(
            comm_state_machine=types.SimpleNamespace(
                action_goal=types.SimpleNamespace(goal_id=types.SimpleNamespace(id=gid))
            )
        )

    def wait_for_result(self, timeout):
        gid = self.gh.comm_state_machine.action_goal.goal_id.id
        status = types.SimpleNamespace(
            status=types.SimpleNamespace(goal_id=types.SimpleNamespace(id=gid), status=4),
            result=types.SimpleNamespace(error="refused: x"),
        )
        FakeClient.results(status)  # the worker answered
        return gid != "g3"  # the client lost the third answer

    def cancel_goal(self):
        pass

    def get_state(self):
        return 4

    def get_result(self):
        return types.SimpleNamespace(error="refused: x")


def test_an_answer_lost_by_the_client_is_a_failure(monkeypatch):
    import asg_scenario.ros_node as ros_node

    monkeypatch.setattr(ros_node, "GoalClient", FakeClient)

    def subscriber(topic, kind, cb, queue_size=None):
        FakeClient.results = cb
        return types.SimpleNamespace(unregister=lambda: None)

    monkeypatch.setattr(rospy, "Subscriber", subscriber)
    monkeypatch.setattr(rospy, "sleep", lambda *a: None)
    out = fuzz_goals.fuzz_goals("/worker_0", 5, seed=1, progress=False)
    assert out["outcomes"]["answered, lost by the client"] == 1 and out["lost_count"] == 1
    assert out["failure_count"] == 1, out["failures"]
    assert out["failures"][0]["why"] == "answered by the worker, lost by the client"
    assert out["outcomes"]["ABORTED"] == 4
