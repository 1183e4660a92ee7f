"""Launch susp_sim_node, optionally a replay of a recorded test drive and a rosbag2 recorder.

For a ROS 2 Jazzy install with this package built in a colcon workspace (README: "In a ROS 2 workspace"):

    ros2 launch susp_sim_ros susp_sim.launch.py                                   # the node alone, wall time
    ros2 launch susp_sim_ros susp_sim.launch.py bag:=drive.mcap rate:=2.0         # node in sim time + replay
    ros2 launch susp_sim_ros susp_sim.launch.py bag:=drive.mcap record_path:=/tmp/run.mcap
    ros2 launch susp_sim_ros susp_sim.launch.py bag:=drive.mcap rosbag_out:=/tmp/run_bag

Launch arguments are listed in ``ARGUMENTS`` (name: default, description). An empty ``vehicle``,
``friction_variant``, ``damper_oil_level`` or ``record_path`` keeps the value of ``params_file``.
The replay is ``susp replay`` (this package's ``susp`` executable) and publishes ``/clock``; with a
``bag`` the node runs in sim time unless ``use_sim_time`` says otherwise, and the launch ends when the
replay ends (``shutdown_after_replay``). The optional recorder is ``ros2 bag record -s mcap`` of the
node's topics, its inputs and the measured IMU.
"""
from __future__ import annotations

import os

from ament_index_python.packages import get_package_prefix, get_package_share_directory
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, EmitEvent, ExecuteProcess, OpaqueFunction, RegisterEventHandler
from launch.event_handlers import OnProcessExit
from launch.events import Shutdown
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node

PACKAGE = "susp_sim_ros"
NODE_EXECUTABLE = "susp_sim_node"   # console_scripts in setup.py, installed to lib/susp_sim_ros
CLI_EXECUTABLE = "susp"

ARGUMENTS = {
    "params_file": ("", "node parameter YAML (default: the package's config/susp_sim_node.yaml)"),
    "vehicle": ("", "vehicle parameter set name or YAML path (empty: from params_file)"),
    "friction_variant": ("", "full | no_horizontal | no_velocity | dahl_only | variant YAML path "
                             "(empty: from params_file)"),
    "damper_oil_level": ("", "FL,FR,RL,RR oil levels in [0, 1], e.g. 1,1,0,0 (empty: from params_file)"),
    "record_path": ("", "MCAP file the node records to (empty: from params_file, i.e. no recording)"),
    "use_sim_time": ("auto", "true | false | auto (auto: true when a bag is replayed)"),
    "bag": ("", "recorded test drive (MCAP) to replay onto the input topics with /clock (empty: no replay)"),
    "rate": ("1.0", "replay speed factor"),
    "loop": ("false", "replay again and again"),
    "replay_wait_s": ("60.0", "the replay waits up to this long [s] for the node's subscriptions "
                              "(the first start compiles the model)"),
    "shutdown_after_replay": ("true", "end the launch when the replay ends"),
    "rosbag_out": ("", "output directory of an additional `ros2 bag record -s mcap` (empty: none)"),
    "discovery_range": ("LOCALHOST", "ROS_AUTOMATIC_DISCOVERY_RANGE of the launched processes: LOCALHOST keeps "
                                     "publishers on other hosts off the node's inputs; SUBNET or SYSTEM_DEFAULT "
                                     "to take inputs from another machine"),
}

RECORDED_TOPICS = ["/sim/imu/data", "/sim/odom", "/sim/suspension", "/diagnostics", "/vehicle/speed",
                   "/vehicle/steering_wheel_angle", "/road/profile", "/road/wheel_heights", "/imu/data", "/clock"]


def _flag(text: str, name: str) -> bool:
    if text.lower() not in ("true", "false"):
        raise ValueError(f"launch argument {name}:={text!r}: expected true or false")
    return text.lower() == "true"


def launch_actions(context):
    """The launch's actions for the launch arguments in ``context`` (node, optional replay and recorder)."""
    arg = {name: LaunchConfiguration(name).perform(context).strip() for name in ARGUMENTS}
    bag = arg["bag"]
    sim_time = bool(bag) if arg["use_sim_time"].lower() == "auto" else _flag(arg["use_sim_time"], "use_sim_time")
    params_file = arg["params_file"] or os.path.join(get_package_share_directory(PACKAGE), "config",
                                                     "susp_sim_node.yaml")
    overrides: dict = {"use_sim_time": sim_time}
    for name in ("vehicle", "friction_variant", "record_path"):
        if arg[name]:
            overrides[name] = arg[name]
    if arg["damper_oil_level"]:
        try:
            overrides["damper_oil_level"] = [float(x) for x in arg["damper_oil_level"].split(",")]
        except ValueError:
            raise ValueError(f"launch argument damper_oil_level:={arg['damper_oil_level']!r}: expected four "
                             "comma-separated numbers FL,FR,RL,RR") from None
    # discovery stays on this host unless asked: a process elsewhere on the same domain publishing steering
    # or speed would otherwise feed the node (the node warns when an input has two publishers)
    env = {"ROS_AUTOMATIC_DISCOVERY_RANGE": arg["discovery_range"]}
    actions = [Node(package=PACKAGE, executable=NODE_EXECUTABLE, name=NODE_EXECUTABLE, output="screen",
                    parameters=[params_file, overrides], additional_env=env)]
    if bag:
        cli = os.path.join(get_package_prefix(PACKAGE), "lib", PACKAGE, CLI_EXECUTABLE)
        cmd = [cli, "replay", bag, "--rate", arg["rate"], "--wait-subscribers", arg["replay_wait_s"]]
        if _flag(arg["loop"], "loop"):
            cmd.append("--loop")
        replay = ExecuteProcess(cmd=cmd, name="susp_replay", output="screen", additional_env=env)
        actions.append(replay)
        if _flag(arg["shutdown_after_replay"], "shutdown_after_replay"):
            actions.append(RegisterEventHandler(OnProcessExit(
                target_action=replay, on_exit=[EmitEvent(event=Shutdown(reason="replay finished"))])))
    if arg["rosbag_out"]:
        cmd = ["ros2", "bag", "record", "-s", "mcap", "-o", arg["rosbag_out"]] + \
            (["--use-sim-time"] if sim_time else []) + ["--topics", *RECORDED_TOPICS]
        actions.append(ExecuteProcess(cmd=cmd, name="rosbag_record", output="screen", additional_env=env))
    return actions


def generate_launch_description() -> LaunchDescription:
    return LaunchDescription(
        [DeclareLaunchArgument(name, default_value=default, description=text)
         for name, (default, text) in ARGUMENTS.items()]
        + [OpaqueFunction(function=launch_actions)])
