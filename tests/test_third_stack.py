"""Issue #55: the third stack (catkin_ws/src/gap_nav) is an ordinary ROS 1 stack that imports
nothing of this project: no asg_* module, message, package dependency or topic of the lockstep
protocol, in any of its files. Its registration (stacks/gap_nav.launch) lives outside it."""

import os
import re

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
STACK = os.path.join(REPO, "catkin_ws", "src", "gap_nav")
#: what would tie a stack to this project: its packages and messages, and the lockstep protocol's
#: topics (a stack without a client never sees them)
TIES = re.compile(r"asg_|asg\.|\b(stack_ack|stack_error|cmd_vel_stamped|labels_gt|ScenarioInfo|VehicleCommand)\b")


def stack_files():
    for root, _, files in os.walk(STACK):
        for f in files:
            yield os.path.join(root, f)


def test_the_third_stack_names_nothing_of_this_project():
    files = list(stack_files())
    assert any(f.endswith("gap_drive") for f in files) and any(f.endswith("package.xml") for f in files)
    found = []
    for path in files:
        with open(path, encoding="utf-8") as fh:
            for n, line in enumerate(fh, 1):
                if TIES.search(line):
                    found.append(f"{os.path.relpath(path, REPO)}:{n}: {line.strip()}")
    assert not found, "the third stack must not use this project:\n" + "\n".join(found)


def test_the_check_would_see_a_tie():
    # the pattern catches what it is for (an import, a message, a protocol topic)
    for line in (
        "from asg_lockstep.ros import LockstepClient",
        "import asg_msgs.msg",
        "<depend>asg_msgs</depend>",
        "rospy.Publisher('stack_ack', ...)",
        "sub('camera/labels_gt')",
    ):
        assert TIES.search(line), line
    for line in ("from geometry_msgs.msg import Twist", "tf2_ros.Buffer()", "<depend>depth_image_proc</depend>"):
        assert not TIES.search(line), line
