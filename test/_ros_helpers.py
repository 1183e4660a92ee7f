"""Launch-free ROS 2 test helpers: isolated environment, private context, a sim-time driver, and for the
tests over real DDS a node in its own process and a probe node that talks to it.

The driver publishes ``/clock`` and the input topics from a second node in the same private context and
spins a ``SingleThreadedExecutor`` until the node under test has taken each message. In sim time the node
applies an input at the ``/clock`` value published before it, when the next ``/clock`` arrives, which is
the lockstep order.
"""
from __future__ import annotations

import os
import random
import signal
import subprocess
import sys
import tempfile
import time

import numpy as np

STOP_TIMEOUT_S = 20.0  # a node process must end this long after SIGINT, else it is killed [s]


def ros_env() -> None:
    """Isolated DDS domain, localhost discovery, writable log dir (before rclpy.init)."""
    os.environ.setdefault("ROS_DOMAIN_ID", str(random.randint(1, 101)))
    os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    os.environ.setdefault("ROS_LOG_DIR", tempfile.mkdtemp(prefix="susp-roslog-"))


def latched_qos():
    """The profile publisher's QoS, as a replay of a recorded drive offers it (transient local, reliable)."""
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
    return QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL, reliability=ReliabilityPolicy.RELIABLE)


def profile_msg(s, zl, zr):
    """A ``/road/profile`` message (``std_msgs/Float64MultiArray``, [channel 3, sample N]) for path
    coordinates ``s`` [m] and elevations ``zl``, ``zr`` [m]."""
    from std_msgs.msg import Float64MultiArray
    from susp_sim_ros.io.messages import road_profile_msg
    from susp_sim_ros.ros.conversion import fill
    return fill(Float64MultiArray(), road_profile_msg(s, zl, zr))


def start_node_process(log_path, module: str, *ros_args: str) -> subprocess.Popen:
    """``module``'s ``main`` (a node entry point) in its own process with ``--ros-args *ros_args``, in the
    isolated environment of :func:`ros_env`; stdout and stderr go to ``log_path``."""
    ros_env()
    log = open(log_path, "w")
    code = f"import sys; from {module} import main; sys.exit(main())"
    return subprocess.Popen([sys.executable, "-c", code, "--ros-args", *ros_args], stdout=log,
                            stderr=subprocess.STDOUT, env=dict(os.environ))


def stop_process(proc: subprocess.Popen) -> int:
    """SIGINT (as Ctrl-C), then its exit code; killed (-9) when it does not end in ``STOP_TIMEOUT_S``."""
    proc.send_signal(signal.SIGINT)
    try:
        return proc.wait(timeout=STOP_TIMEOUT_S)
    except subprocess.TimeoutExpired:
        proc.kill()
        return -9


class Probe:
    """A plain rclpy node in a private context with its executor, publishing the test-drive inputs
    (``speed``, ``steer``, the latched ``profile``) to a node in another process."""

    def __init__(self, name: str):
        ros_env()
        import rclpy
        from rclpy.executors import SingleThreadedExecutor
        from std_msgs.msg import Float64, Float64MultiArray
        self.rclpy, self.Float64 = rclpy, Float64
        self.ctx = rclpy.Context()
        rclpy.init(context=self.ctx)
        self.node = rclpy.create_node(name, context=self.ctx)
        self.steer = self.node.create_publisher(Float64, "/vehicle/steering_wheel_angle", 10)
        self.speed = self.node.create_publisher(Float64, "/vehicle/speed", 10)
        self.profile = self.node.create_publisher(Float64MultiArray, "/road/profile", latched_qos())
        self.ex = SingleThreadedExecutor(context=self.ctx)
        self.ex.add_node(self.node)

    def wait_for(self, ready, procs: dict, timeout: float, what: str) -> None:
        """Spin until ``ready()``; fails with the log of a process of ``procs`` (log path -> process)
        that ended, or after ``timeout`` [s]."""
        end = time.monotonic() + timeout
        while not ready():
            for log, proc in procs.items():
                assert proc.poll() is None, log.read_text()
            assert time.monotonic() < end, what
            self.ex.spin_once(timeout_sec=0.05)

    def drive(self, seconds: float, speed: float, steer: float) -> None:
        """Publish ``speed`` [m/s] and ``steer`` [rad] about every 10 ms for ``seconds`` [s], spinning."""
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            self.steer.publish(self.Float64(data=float(steer)))
            self.speed.publish(self.Float64(data=float(speed)))
            self.ex.spin_once(timeout_sec=0.01)

    def close(self) -> None:
        try:
            self.ex.shutdown()
            self.node.destroy_node()
        finally:
            self.rclpy.try_shutdown(context=self.ctx)


class SimDriver:
    """A :class:`SuspSimNode` in a private context, fed by a driver node; collects ``/sim/imu/data``."""

    def __init__(self, params: dict | None = None, *, sim_time: bool = True):
        ros_env()
        import rclpy
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.parameter import Parameter
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
        latched = latched_qos()
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
        self.wait_delivered()

    def wait_delivered(self, timeout: float = 5.0) -> None:
        """Spin until every ``/sim/imu/data`` sample the node published has reached the driver: under load a
        sample published on the last ``/clock`` may still be in DDS after a few idle spins."""
        self.spin_until(lambda: len(self.imu) >= self.node.published, timeout)

    def spin_idle(self, n: int = 3) -> None:
        for _ in range(n):
            self.ex.spin_once(timeout_sec=0.0)

    def send(self, topic: str, msg) -> None:
        before = self.node.inputs.inputs_taken
        self.pub[topic].publish(msg)
        self.spin_until(lambda: self.node.inputs.inputs_taken > before)

    def send_value(self, topic: str, value: float) -> None:
        self.send(topic, self.Float64(data=float(value)))

    def send_profile(self, s, zl, zr) -> None:
        self.send("/road/profile", profile_msg(s, zl, zr))

    def wait_samples(self, n: int, timeout: float = 10.0) -> None:
        self.spin_until(lambda: len(self.imu) >= n, timeout)

    def imu_arrays(self):
        t = np.array([m.header.stamp.sec * 1_000_000_000 + m.header.stamp.nanosec for m in self.imu], dtype=np.int64)
        g = np.array([[m.angular_velocity.x, m.angular_velocity.y, m.angular_velocity.z] for m in self.imu])
        return t, g.reshape(-1, 3)

    def play(self, drive, *, clock_step_ns: int | None = None) -> None:
        """Feed a TestDrive as a sim-time replay would: /clock to each message time (and every
        ``clock_step_ns`` in between when given), then the message; finally the clock to the end."""
        from susp_sim_ros.runtime.lockstep import _events
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
