"""Launch-free ROS 2 test helpers: isolated environment, private context, a sim-time driver.

The driver publishes ``/clock`` and the input topics from a second node in the same private context and
spins a ``SingleThreadedExecutor`` until the node under test has taken each message. In sim time the node
applies an input at the ``/clock`` value published before it, when the next ``/clock`` arrives, which is
the lockstep order.
"""
from __future__ import annotations

import os
import random
import tempfile
import time

import numpy as np


def ros_env() -> None:
    """Isolated DDS domain, localhost discovery, writable log dir (before rclpy.init)."""
    os.environ.setdefault("ROS_DOMAIN_ID", str(random.randint(1, 101)))
    os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    os.environ.setdefault("ROS_LOG_DIR", tempfile.mkdtemp(prefix="susp-roslog-"))


class SimDriver:
    """A :class:`SuspSimNode` in a private context, fed by a driver node; collects ``/sim/imu/data``."""

    def __init__(self, params: dict | None = None, *, sim_time: bool = True):
        ros_env()
        import rclpy
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.parameter import Parameter
        from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
        from rosgraph_msgs.msg import Clock
        from sensor_msgs.msg import Imu
        from std_msgs.msg import Float64, Float64MultiArray
        from susp_sim_ros.ros.node import SuspSimNode

        self.rclpy = rclpy
        self.ctx = rclpy.Context()
        rclpy.init(context=self.ctx)
        overrides = [Parameter("use_sim_time", value=sim_time)]
        overrides += [Parameter(k, value=v) for k, v in (params or {}).items()]
        self.node = SuspSimNode(context=self.ctx, parameter_overrides=overrides, start_thread=False)
        self.drv = rclpy.create_node("test_driver", context=self.ctx)
        latched = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL,
                             reliability=ReliabilityPolicy.RELIABLE)
        self.pub_clock = self.drv.create_publisher(Clock, "/clock", 100)
        steer = "/vehicle/steering_wheel_angle"
        self.pub = {"/vehicle/speed": self.drv.create_publisher(Float64, "/vehicle/speed", 100),
                    steer: self.drv.create_publisher(Float64, steer, 100),
                    "/road/profile": self.drv.create_publisher(Float64MultiArray, "/road/profile", latched),
                    "/road/wheel_heights": self.drv.create_publisher(Float64MultiArray, "/road/wheel_heights", 100)}
        self.imu: list = []
        self.drv.create_subscription(Imu, "/sim/imu/data", self.imu.append, 1000)
        self.Clock, self.Float64, self.Float64MultiArray = Clock, Float64, Float64MultiArray
        self.ex = SingleThreadedExecutor(context=self.ctx)
        self.ex.add_node(self.node)
        self.ex.add_node(self.drv)
        self.n_inputs = 0
        self._wait_connected()

    def _wait_connected(self, timeout: float = 10.0) -> None:
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            if all(p.get_subscription_count() > 0 for p in self.pub.values()) \
                    and self.pub_clock.get_subscription_count() > 0 \
                    and self.drv.count_publishers("/sim/imu/data") > 0 and self._imu_matched():
                return
            self.ex.spin_once(timeout_sec=0.01)
        raise TimeoutError("driver and node did not discover each other")

    def _imu_matched(self) -> bool:
        return self.node.pub_imu.get_subscription_count() > 0

    def spin_until(self, cond, timeout: float = 5.0) -> None:
        end = time.monotonic() + timeout
        while not cond():
            if time.monotonic() > end:
                raise TimeoutError("condition not reached while spinning")
            self.ex.spin_once(timeout_sec=0.005)

    def clock(self, t_ns: int) -> None:
        msg = self.Clock()
        msg.clock.sec, msg.clock.nanosec = divmod(int(t_ns), 1_000_000_000)
        self.pub_clock.publish(msg)
        self.spin_until(lambda: self.node.now_ns() == int(t_ns))
        self.spin_idle()

    def spin_idle(self, n: int = 3) -> None:
        for _ in range(n):
            self.ex.spin_once(timeout_sec=0.0)

    def send(self, topic: str, msg) -> None:
        before = self.node.inputs_taken
        self.pub[topic].publish(msg)
        self.spin_until(lambda: self.node.inputs_taken > before)

    def send_value(self, topic: str, value: float) -> None:
        self.send(topic, self.Float64(data=float(value)))

    def send_profile(self, s, zl, zr) -> None:
        from std_msgs.msg import MultiArrayDimension
        m = self.Float64MultiArray()
        n = len(s)
        m.layout.dim = [MultiArrayDimension(label="channel", size=3, stride=3 * n),
                        MultiArrayDimension(label="sample", size=n, stride=n)]
        m.data = [float(x) for x in np.concatenate([s, zl, zr])]
        self.send("/road/profile", m)

    def wait_samples(self, n: int, timeout: float = 10.0) -> None:
        self.spin_until(lambda: len(self.imu) >= n, timeout)

    def imu_arrays(self):
        t = np.array([m.header.stamp.sec * 1_000_000_000 + m.header.stamp.nanosec for m in self.imu], dtype=np.int64)
        g = np.array([[m.angular_velocity.x, m.angular_velocity.y, m.angular_velocity.z] for m in self.imu])
        return t, g.reshape(-1, 3)

    def play(self, drive, *, clock_step_ns: int | None = None) -> None:
        """Feed a TestDrive as a sim-time replay would: /clock to each message time (and every
        ``clock_step_ns`` in between when given), then the message; finally the clock to the end."""
        from susp_sim_ros.lockstep import _events
        t_prev = None
        road = drive.road
        for t, kind, i in _events(drive):
            if t != t_prev:
                if clock_step_ns and t_prev is not None:
                    for tc in range(t_prev + clock_step_ns, t, clock_step_ns):
                        self.clock(tc)
                self.clock(t)
                t_prev = t
            if kind == 0:
                self.send_profile(road.s, road.zl, road.zr)
            elif kind == 1:
                self.send_value("/vehicle/speed", drive.speed.values[i])
            elif kind == 2:
                self.send_value("/vehicle/steering_wheel_angle", drive.steering.values[i])
        self.clock(drive.t_end_ns)

    def close(self) -> None:
        try:
            self.ex.shutdown()
            self.node.destroy_node()
            self.drv.destroy_node()
        finally:
            self.rclpy.try_shutdown(context=self.ctx)
