"""The console entry points' common part: run one node in its own context until SIGINT/SIGTERM.

:func:`run_node` is ``main`` of ``susp_sim_node`` and ``susp_damper_controller``: init rclpy, build the
node, spin a ``SingleThreadedExecutor``, turn a bad parameter into a one-line error and exit code 2 (never
a traceback), destroy the node and shut rclpy down on every path. A signal that shuts the context down
while the executor is between two waits is a normal stop (exit code 0), not a traceback.
"""
from __future__ import annotations

import sys
import time
from collections.abc import Callable
from typing import TypeVar

import rclpy
from rclpy.utilities import remove_ros_args
from rclpy.exceptions import InvalidParameterValueException
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.node import Node

from ..errors import SuspInputError
from .timing import SWITCH_INTERVAL_S, freeze_start_up_heap

N = TypeVar("N", bound=Node)
SPIN_TIMEOUT_S = 0.1  # the loop checks ``rclpy.ok()`` and ``stop_when`` at least this often [s]


def wants_help(args: list[str]) -> bool:
    """``-h`` or ``--help`` among the arguments outside ``--ros-args ... [--]``."""
    return any(a in ("-h", "--help") for a in remove_ros_args(args)[1:])


def usage(name: str, summary: str, parameters: dict[str, tuple[object, str]]) -> str:
    """The ``--help`` text of a node: what it is, how to set its parameters, each with default and meaning."""
    width = max(len(k) for k in parameters)
    rows = "\n".join(f"  {k:<{width}}  {d}  (default: {v!r})" for k, (v, d) in parameters.items())
    return (f"usage: {name} [--ros-args -p NAME:=VALUE ...]\n\n{summary}\n\nparameters:\n{rows}\n\n"
            "Topics, types and units: README.md, 'The node'. Exit codes: 0 on SIGINT/SIGTERM, 2 on a bad parameter.")


def run_node(make_node: Callable[[], N], name: str, args: list[str] | None = None, *, realtime: bool = False,
             stop_when: Callable[[N], bool] = lambda node: False,
             finish: Callable[[N, Callable[[float], None]], int] = lambda node, spin_for: 0,
             help_text: str = "") -> int:
    """Run the node ``make_node()`` (``name`` in error messages) with the command line ``args`` (default
    ``sys.argv``) until SIGINT/SIGTERM or ``stop_when(node)``; then return ``finish(node, spin_for)``
    (``spin_for(seconds)`` keeps the node spinning a little longer, e.g. so a last message reaches its
    subscribers). Returns 0 on SIGINT/SIGTERM, 2 when the node refuses a parameter (message on stderr).

    ``realtime``: a shorter interpreter switch interval (:data:`.timing.SWITCH_INTERVAL_S`) and the
    start-up objects collected and frozen out of the garbage collector's way before the executor first
    spins (:func:`.timing.freeze_start_up_heap`: no 100-200 ms full collection in real time).
    ``help_text``: printed (exit 0, no node started) for ``-h``/``--help`` outside ``--ros-args``."""
    argv = list(args if args is not None else sys.argv)
    if wants_help(argv):
        print(help_text or f"usage: {name} [--ros-args -p NAME:=VALUE ...]")
        return 0
    if realtime:
        sys.setswitchinterval(SWITCH_INTERVAL_S)
    rclpy.init(args=argv)
    node = None
    try:
        node = make_node()
        executor = SingleThreadedExecutor()
        executor.add_node(node)
        if realtime:
            freeze_start_up_heap()
        while rclpy.ok() and not stop_when(node):
            executor.spin_once(timeout_sec=SPIN_TIMEOUT_S)

        def spin_for(seconds: float) -> None:
            end = time.monotonic() + seconds
            while rclpy.ok() and time.monotonic() < end:
                executor.spin_once(timeout_sec=0.05)
        return finish(node, spin_for)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except (SuspInputError, InvalidParameterValueException) as exc:
        print(f"{name}: error: {exc}", file=sys.stderr)
        return 2
    except Exception:
        # rclpy's SIGINT/SIGTERM handler shuts the context down at any moment, also between the loop's
        # ``rclpy.ok()`` and the executor's next wait, which then fails to create its timeout timer
        # (RCLError "the given context is not valid"). That is the requested shutdown, not a failure.
        if rclpy.ok():
            raise
    finally:
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
    return 0
