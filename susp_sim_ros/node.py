"""The old import path of the node: the node lives in the package :mod:`susp_sim_ros.ros`
(:mod:`susp_sim_ros.ros.node`, entry point ``susp_sim_node = susp_sim_ros.ros.node:main``). Kept so that
console scripts installed before the move and ``python -m susp_sim_ros.node`` keep working; new code
imports from :mod:`susp_sim_ros.ros`."""
from __future__ import annotations

import sys

from .ros.node import NODE_NAME, SuspSimNode, main
from .ros.parameters import DEFAULTS, RUNTIME
from .ros.recording import RECORD_REORDER_NS, RecordingQueue
from .ros.timing import TimingStats, raise_priority

__all__ = ["DEFAULTS", "NODE_NAME", "RECORD_REORDER_NS", "RUNTIME", "RecordingQueue", "SuspSimNode",
           "TimingStats", "main", "raise_priority"]

if __name__ == "__main__":
    sys.exit(main())
