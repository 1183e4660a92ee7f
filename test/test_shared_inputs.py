"""Two publishers on one input topic (another process on the same ROS domain): the node says so in its
log and on /diagnostics, and with ``refuse_shared_inputs`` refuses the topic's messages until one
publisher is left. A node in a private context, the publishers its own (DDS discovery within the process)."""
from __future__ import annotations

import time

import pytest
from std_msgs.msg import Float64

from _ros_helpers import ros_env

SPEED = "/vehicle/speed"


class _Logger:
    def __init__(self):
        self.lines: list[tuple[str, str]] = []

    def warning(self, text):
        self.lines.append(("warning", text))

    def info(self, text):
        self.lines.append(("info", text))


@pytest.fixture(params=[False, True], ids=["warn", "refuse"])
def node_and_context(request):
    ros_env()
    import rclpy
    from rclpy.parameter import Parameter

    from susp_sim_ros.ros.node import SuspSimNode
    ctx = rclpy.Context()
    rclpy.init(context=ctx)
    over = [Parameter("realtime_priority", value=0), Parameter("refuse_shared_inputs", value=request.param)]
    node = SuspSimNode(context=ctx, parameter_overrides=over, start_thread=False)
    helpers = [rclpy.create_node(f"driver_{k}", context=ctx) for k in range(2)]
    yield node, helpers, request.param
    for n in (node, *helpers):
        n.destroy_node()
    rclpy.shutdown(context=ctx)


def _inputs_status(node) -> dict:
    return next(s for s in node.diagnostics() if s["name"].endswith("inputs"))


def _wait_publishers(node, n: int) -> None:
    end = time.monotonic() + 5.0
    while node.count_publishers(SPEED) != n and time.monotonic() < end:
        time.sleep(0.05)
    assert node.count_publishers(SPEED) == n


def test_two_publishers_on_one_input_are_reported_and_refused_when_asked(node_and_context):
    node, (a, b), refuse = node_and_context
    log = _Logger()
    node.get_logger = lambda: log  # the node's own logger writes to stderr; read what it says here
    pub_a = a.create_publisher(Float64, SPEED, 10)
    _wait_publishers(node, 1)
    status = _inputs_status(node)
    assert status["values"]["shared_inputs"] == "" and "more than one publisher" not in status["message"]
    node.inputs.on_speed(Float64(data=5.0), None)
    assert node.core.rejections.get("shared_input", 0) == 0

    pub_b = b.create_publisher(Float64, SPEED, 10)
    _wait_publishers(node, 2)
    status = _inputs_status(node)
    assert status["level"] == 1 and status["values"]["shared_inputs"] == SPEED
    assert f"{SPEED}=2" in status["values"]["publishers"] and "more than one publisher" in status["message"]
    warned = [t for lvl, t in log.lines if lvl == "warning" and SPEED in t and "2 publishers" in t]
    assert len(warned) == 1
    _inputs_status(node)  # the warning is said once, not at every diagnostics period
    assert len([t for lvl, t in log.lines if lvl == "warning" and SPEED in t]) == 1
    node.inputs.on_speed(Float64(data=6.0), None)
    assert node.core.rejections.get("shared_input", 0) == (1 if refuse else 0)

    b.destroy_publisher(pub_b)
    _wait_publishers(node, 1)
    assert _inputs_status(node)["values"]["shared_inputs"] == ""
    assert any(lvl == "info" and "one publisher again" in t for lvl, t in log.lines)
    node.inputs.on_speed(Float64(data=7.0), None)
    assert node.core.rejections.get("shared_input", 0) == (1 if refuse else 0)
    a.destroy_publisher(pub_a)
