"""``susp_damper_controller``: a reference semi-active damper controller as its own ROS 2 node (issue 15).

Subscribes ``/sim/imu/data`` (body rates and specific force at the centre of gravity) and
``/sim/suspension`` (deflection and its rate per corner) of ``susp_sim_node`` and, on every suspension
sample, publishes ``/vehicle/damper_command`` (``std_msgs/msg/Float64MultiArray``, [FL, FR, RL, RR] in
[0, 1]) from one of the library controllers (:mod:`susp_sim_ros.control.controllers`)::

    susp_damper_controller --ros-args -p controller:=skyhook

Parameters: ``controller`` (skyhook, skyhook_onoff, groundhook, add, sh_add; passive publishes nothing),
``sample_time_s`` (the period of the samples it gets: the simulation node's publish period, default
0.01 s), ``vehicle`` (geometry of the corners; default passat_b8_like). A thin shell: the control law is
the same code the offline ride runs and studies use.
"""
from __future__ import annotations

import dataclasses
import sys

import numpy as np
from rcl_interfaces.msg import FloatingPointRange, ParameterDescriptor
from rclpy.node import Node
from sensor_msgs.msg import Imu
from std_msgs.msg import Float64MultiArray, MultiArrayDimension

from ..control.controllers import CONTROLLERS, Measurement, load_controller_params, make_controller
from ..errors import SuspInputError
from ..io.messages import SUSPENSION_QUANTITIES
from ..model.params import load_vehicle
from ..model.semiactive import load_damper_family
from ..runtime.sim_core import DAMPER_COMMAND, SIM_IMU, SIM_SUSPENSION
from .qos import OUTPUT_QOS as QOS  # the same profile as the simulation's outputs (reliable, depth 50)
from .run import run_node, usage
from ..model.params import DEFAULT_VEHICLE

NODE_NAME = "susp_damper_controller"
MAX_SAMPLE_TIME_S = 0.1  # a sample period longer than this is no semi-active control any more [s]
_Q = len(SUSPENSION_QUANTITIES)
_DEFL, _DEFL_VEL = SUSPENSION_QUANTITIES.index("deflection"), SUSPENSION_QUANTITIES.index("deflection_velocity")


HELP_SUMMARY = ("Semi-active damper controller: reads /sim/imu and /sim/suspension, publishes "
                "/vehicle/damper_command (FL, FR, RL, RR in [0, 1]).")
#: name -> (default, description) of the parameters, for ``--help`` and the descriptors
PARAMETERS: dict[str, tuple[object, str]] = {
    "controller": ("skyhook", "damper controller: " + ", ".join(CONTROLLERS)),
    "sample_time_s": (0.01, "period of the /sim samples [s] (the simulation's publish period)"),
    "vehicle": (DEFAULT_VEHICLE, "vehicle parameter set (corner geometry)"),
}


class DamperControllerNode(Node):
    def __init__(self, **kwargs):
        super().__init__(NODE_NAME, **kwargs)
        # read at start only, so read-only; rclpy checks the range, the strict lower bound is checked here
        period = [FloatingPointRange(from_value=0.0, to_value=MAX_SAMPLE_TIME_S, step=0.0)]
        self.declare_parameter("controller", PARAMETERS["controller"][0], ParameterDescriptor(
            description="damper controller", read_only=True, additional_constraints=", ".join(CONTROLLERS)))
        self.declare_parameter("sample_time_s", PARAMETERS["sample_time_s"][0], ParameterDescriptor(
            description=PARAMETERS["sample_time_s"][1], read_only=True, floating_point_range=period))
        self.declare_parameter("vehicle", PARAMETERS["vehicle"][0], ParameterDescriptor(
            description=PARAMETERS["vehicle"][1], read_only=True))
        name = str(self.get_parameter("controller").value)
        dt = float(self.get_parameter("sample_time_s").value)
        if not (np.isfinite(dt) and 0 < dt <= MAX_SAMPLE_TIME_S):
            raise SuspInputError(f"parameter sample_time_s: expected a period in (0, {MAX_SAMPLE_TIME_S:g}] s, "
                                 f"got {dt}")
        params = dataclasses.replace(load_controller_params(), sample_time=dt)
        self.controller = make_controller(name, load_vehicle(str(self.get_parameter("vehicle").value)),
                                          load_damper_family(), params)
        self._imu: Imu | None = None
        self.commands = 0
        self.pub = self.create_publisher(Float64MultiArray, DAMPER_COMMAND, QOS)
        self.create_subscription(Imu, SIM_IMU, self._on_imu, QOS)
        self.create_subscription(Float64MultiArray, SIM_SUSPENSION, self._on_suspension, QOS)
        self._msg = Float64MultiArray()
        self._msg.layout.dim = [MultiArrayDimension(label="wheel", size=4, stride=4)]
        self.get_logger().info(f"{NODE_NAME}: {name} at {dt * 1e3:g} ms samples")

    def _on_imu(self, msg: Imu) -> None:
        self._imu = msg

    def _on_suspension(self, msg: Float64MultiArray) -> None:
        if self._imu is None or len(msg.data) != 4 * _Q:
            return
        d = np.asarray(msg.data, float).reshape(4, _Q)
        imu = self._imu
        m = Measurement(imu.linear_acceleration.z, imu.angular_velocity.x, imu.angular_velocity.y,
                        d[:, _DEFL], d[:, _DEFL_VEL])
        cmd = self.controller(m)
        if cmd is None:
            return
        self._msg.data = [float(x) for x in cmd]
        self.pub.publish(self._msg)
        self.commands += 1


def main(args: list[str] | None = None) -> int:
    """Console entry point ``susp_damper_controller [--ros-args ...]``. Exit 0 on SIGINT/SIGTERM, 2 on a
    bad parameter."""
    # real time too: a full garbage collection in the controller would hold its commands back as well
    return run_node(DamperControllerNode, NODE_NAME, args, realtime=True,
                    help_text=usage(NODE_NAME, HELP_SUMMARY, PARAMETERS))


if __name__ == "__main__":
    sys.exit(main())
