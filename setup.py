"""The colcon (ament_python) build of the package: what pyproject.toml cannot say.

pip reads everything from pyproject.toml (packages, entry points, dependencies); colcon runs this
file, which adds the ament index marker, package.xml, the launch files and the parameter files
under share/homeo_robot/ (ROS 2's layout: `ros2 pkg`, `ros2 launch`, `ros2 param load` find them
there). setup.cfg puts the console scripts under lib/homeo_robot/ for `ros2 run`.
"""

from glob import glob

from setuptools import setup

PACKAGE = "homeo_robot"

setup(
    python_requires=">=3.11,<3.13",  # here, not in pyproject.toml (see its note): Jazzy's Python 3.12, and 3.11
    data_files=[
        ("share/ament_index/resource_index/packages", [f"resource/{PACKAGE}"]),
        (f"share/{PACKAGE}", ["package.xml"]),
        (f"share/{PACKAGE}/launch", sorted(glob("launch/*.launch.py"))),
        (f"share/{PACKAGE}/config", sorted(glob("config/*.yaml"))),
    ],
)
