from catkin_pkg.python_setup import generate_distutils_setup
from setuptools import setup

setup(
    **generate_distutils_setup(
        packages=[
            "asg_agent",
            "asg_agent.search",
            "asg_agent.scoring",
            "asg_agent.campaign",
            "asg_agent.records",
            "asg_agent.ros",
            "asg_agent.cli",
        ],
        package_dir={"": "src"},
    )
)
