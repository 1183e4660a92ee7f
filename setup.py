"""ament_python / pip package definition for susp_sim_ros.

Works both in a ROS 2 Jazzy colcon workspace (data_files install the ament index marker, package.xml,
config, the launch file and the Foxglove layout under share/) and as a plain pip install into a venv
with the ROS 2 Jazzy PyPI wheels.
"""
from glob import glob

from setuptools import find_packages, setup

package_name = "susp_sim_ros"

setup(
    name=package_name,
    version="0.1.0",
    packages=find_packages(exclude=["test", "test.*", "benchmarks", "truth_generators", "truth_generators.*"]),
    package_data={package_name: ["model/_kernel_template.py"]},
    data_files=[
        ("share/ament_index/resource_index/packages", ["resource/" + package_name]),
        ("share/" + package_name, ["package.xml"]),
        ("share/" + package_name + "/config", glob("config/*.yaml")),
        ("share/" + package_name + "/config/vehicles", glob("config/vehicles/*.yaml")),
        ("share/" + package_name + "/config/variants", glob("config/variants/*.yaml")),
        ("share/" + package_name + "/config/studies", glob("config/studies/*.yaml")),
        ("share/" + package_name + "/config/topic_maps", glob("config/topic_maps/*.yaml")),
        ("share/" + package_name + "/launch", glob("launch/*.launch.py")),
        ("share/" + package_name + "/foxglove", glob("foxglove/*.json")),
    ],
    install_requires=["setuptools", "numpy", "scipy", "pyyaml", "matplotlib", "numba", "mcap",
                      "mcap-ros2-support", "tqdm", "dask[distributed]", "rosbags"],
    zip_safe=False,
    maintainer="susp_sim_ros developers",
    maintainer_email="dev@susp-sim-ros.invalid",
    description="Real-time five-mass vehicle model with phenomenological suspension friction for ROS 2",
    license="Apache-2.0",
    extras_require={
        "test": ["pytest", "hypothesis", "rosbags", "asammdf", "pyopencrg", "ruff>=0.15,<0.18", "mypy>=2.0,<3"],
        # susp import: ASAM MDF4 drives (asammdf) and OpenCRG roads (pyopencrg)
        "import": ["asammdf", "pyopencrg"],
        "bench": ["commonroad-vehicle-models"],
    },
    entry_points={
        "console_scripts": [
            "susp = susp_sim_ros.cli.main:main",
            "susp_sim_node = susp_sim_ros.ros.node:main",
            "susp_damper_controller = susp_sim_ros.ros.controller_node:main",
        ],
    },
)
