"""Issue #39: the depth stack is a stack a user could have written: it imports standard ROS
packages, numpy and itself, and of this project only asg_lockstep, the package a stack adds to
run in lockstep: its client and its parameter tables (issue #56)."""

import ast
import glob
import os

HERE = os.path.dirname(os.path.abspath(__file__))
ALLOWED_ROOTS = {
    "math",
    "numpy",
    "rospy",
    "tf2_ros",
    "geometry_msgs",
    "nav_msgs",
    "visualization_msgs",  # standard: its rviz markers
    "sensor_msgs",
    "dataclasses",
    "typing",
}
ALLOWED_PROJECT = {
    "asg_lockstep.ros",
    "asg_lockstep.params",
    "asg_depth_stack",
    "asg_depth_stack.arcs",
    "asg_depth_stack.grid",
    "asg_depth_stack.node",
    "asg_depth_stack.params",
}


def imports(path):
    for node in ast.walk(ast.parse(open(path).read(), path)):
        if isinstance(node, ast.Import):
            yield from (a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            yield node.module


def test_the_depth_stack_imports_nothing_of_this_project_but_the_lockstep_client():
    files = glob.glob(os.path.join(HERE, "..", "src", "asg_depth_stack", "*.py"))
    files += [os.path.join(HERE, "..", "scripts", "depth_stack")]
    assert len(files) >= 4
    seen = set()
    for f in files:
        for name in imports(f):
            seen.add(name)
            if name in ALLOWED_PROJECT:
                continue
            assert name.split(".")[0] in ALLOWED_ROOTS, f"{os.path.basename(f)} imports {name}"
    assert "asg_lockstep.ros" in seen  # the one thing of the project, where stated
