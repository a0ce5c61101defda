#!/usr/bin/python3
"""rostest (issue #53): the planner's stack_ack waits for its inputs' publishers. A segmenter that
starts late acked once the worker listened to its labels, before the planner's link was up; the
first labels were lost and the run ended on the command timeout. Here the test plays the worker:
it announces a scenario every 0.5 s, as the scene worker does, and counts the acks."""

import time
import unittest

import rospy
import rostest
from asg_msgs.msg import ScenarioInfo, StackAck, Tick
from nav_msgs.msg import Odometry
from sensor_msgs.msg import Image

ANNOUNCE_S = 0.5  # [s] the scene worker's repeat period


class PlannerAck(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("planner_ack_test")
        cls.acks = {"ack_a": [], "ack_b": []}
        cls.announce = {}
        for ns in cls.acks:
            rospy.Subscriber(f"/{ns}/stack_ack", StackAck, lambda m, ns=ns: cls.acks[ns].append(m))
            cls.announce[ns] = rospy.Publisher(f"/{ns}/scenario", ScenarioInfo, queue_size=1, latch=True)

    def info(self, scenario_id):
        return ScenarioInfo(
            scenario_id=scenario_id,
            run=1,
            base_stamp=rospy.Time(1000 + scenario_id * 5000),
            camera_width=256,
            camera_height=256,
            landscape_size=100.0,
            goal_x=90.0,
            goal_y=50.0,
            goal_radius=3.0,
            speed=2.0,
        )

    def announce_until(self, ns, scenario_id, seconds, stop_at_ack=True):
        """Announces every ANNOUNCE_S for up to `seconds`; returns the announcements sent before the
        first ack of this scenario (None: no ack)."""
        self.wait_for_planner(ns)
        sent = 0
        t_end = time.time() + seconds
        while time.time() < t_end:
            self.announce[ns].publish(self.info(scenario_id))
            sent += 1
            time.sleep(ANNOUNCE_S)
            if stop_at_ack and [a for a in self.acks[ns] if a.scenario_id == scenario_id]:
                return sent
        return None

    def wait_for_planner(self, ns):
        deadline = time.time() + 30.0
        while self.announce[ns].get_num_connections() == 0:
            self.assertLess(time.time(), deadline, f"/{ns}/planner never subscribed to scenario")
            time.sleep(0.1)

    def test_1_no_ack_until_every_input_has_a_publisher(self):
        ns = "ack_a"
        # no depth, labels, odometry or tick publisher yet: 3 announcements go unanswered
        self.announce_until(ns, 11, 3 * ANNOUNCE_S, stop_at_ack=False)
        self.assertEqual([a for a in self.acks[ns] if a.scenario_id == 11], [])
        pubs = [
            rospy.Publisher(f"/{ns}/camera/depth/image_raw", Image, queue_size=1),
            rospy.Publisher(f"/{ns}/labels", Image, queue_size=1),
            rospy.Publisher(f"/{ns}/odom", Odometry, queue_size=1),
        ]
        time.sleep(1.0)  # their links come up
        # three of the four: still none (no tick publisher); 5 announcements deferred so far
        self.announce_until(ns, 11, 2 * ANNOUNCE_S, stop_at_ack=False)
        self.assertEqual([a for a in self.acks[ns] if a.scenario_id == 11], [])
        pubs.append(rospy.Publisher(f"/{ns}/tick", Tick, queue_size=1))
        time.sleep(1.0)
        # the next announcement, the 6th, is acked: the give-up path would need a 7th
        self.assertEqual(self.announce_until(ns, 11, 3.0), 1)
        # the next scenario, links up: acked at its first announcement
        self.assertEqual(self.announce_until(ns, 12, 3.0), 1)
        del pubs

    def test_2_after_about_3_s_without_an_input_it_acks_anyway_and_never_waits_again(self):
        ns = "ack_b"  # no input publisher at all
        t0 = time.time()
        sent = self.announce_until(ns, 21, 8.0)
        self.assertIsNotNone(sent, "a planner without input publishers never acked")
        self.assertGreaterEqual(sent, 7)  # 6 announcements deferred, ~3 s
        self.assertGreater(time.time() - t0, 3.0)
        self.assertEqual(self.announce_until(ns, 22, 3.0), 1)  # from then on, at once


if __name__ == "__main__":
    rostest.rosrun("asg_tests", "planner_ack", PlannerAck)
