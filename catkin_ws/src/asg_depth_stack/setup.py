from catkin_pkg.python_setup import generate_distutils_setup
from setuptools import setup

setup(**generate_distutils_setup(packages=["asg_depth_stack"], package_dir={"": "src"}))
