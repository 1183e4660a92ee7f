"""Two places where the node needs more than rclpy's everyday API, kept here with the reason.

- :func:`guard_time_source` (public API only: ``Node.subscriptions``, ``Subscription.topic_name`` and
  ``.callback``): with ``use_sim_time`` rclpy's own time source subscribes to ``/clock`` and raises on a
  negative time (``Time.from_msg``), which would take the executor and the node down. Its callback is
  wrapped so it sees only valid times; the node's own ``/clock`` subscription rejects and counts the others.
- :func:`take_pending`: **uses rclpy below its documented Python API** (``Subscription.handle`` and the
  ``take_message`` method of the C binding, exactly as ``rclpy.executors.Executor`` does). Before a due
  ``/clock`` is processed in sim time, every message DDS already holds for the input subscriptions must
  be in the reorder queue (:mod:`.sim_time`): a lagging executor takes only one message per
  subscription per round, so an input published before the clock could otherwise be applied after it.
  rclpy Jazzy has no public way to take a message outside the executor (rclcpp has
  ``Subscription::take``; rclpy has none, and an executor cannot be spun from inside its own callback).
  Checked against rclpy 7.1.5: ``raw=True`` only changes what a callback receives (CDR bytes), the
  ``MessageInfo`` (its ``source_timestamp`` orders the queue) reaches callbacks only, and
  :mod:`rclpy.serialization` converts bytes but takes nothing from DDS; a second node with its own executor
  would move the input subscriptions off ``susp_sim_node`` in the ROS graph.
"""
from __future__ import annotations

from collections.abc import Iterable

from rclpy.exceptions import InvalidHandle
from rclpy.node import Node
from rclpy.subscription import Subscription
from rosgraph_msgs.msg import Clock

from .conversion import clock_time_ns


def guard_time_source(node: Node) -> int:
    """Wrap the callbacks of the node's existing ``/clock`` subscriptions (rclpy's time source: call this
    before creating one's own) so that they see only valid times. Returns how many were wrapped."""
    wrapped = 0
    for sub in node.subscriptions:
        if sub.topic_name != "/clock":
            continue
        inner = sub.callback

        def guarded(msg: Clock, inner=inner) -> None:
            if clock_time_ns(msg) is not None:
                inner(msg)
        sub.callback = guarded
        wrapped += 1
    return wrapped


def take_pending(subscriptions: Iterable[Subscription]) -> None:
    """Take every message already delivered to ``subscriptions`` (callbacks with message info) and pass
    it to their callbacks, as the executor would (which then finds them empty)."""
    try:
        for sub in subscriptions:
            while True:
                with sub.handle:
                    got = sub.handle.take_message(sub.msg_type, sub.raw)
                if got is None:
                    break
                sub.callback(*got)
    except InvalidHandle:  # shutting down: a subscription is already destroyed
        pass
