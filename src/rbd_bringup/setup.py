# Do not run directly: catkin_python_setup() calls it.
from catkin_pkg.python_setup import generate_distutils_setup
from setuptools import setup

setup(**generate_distutils_setup(packages=["rbd_bringup"], package_dir={"": "src"}))
