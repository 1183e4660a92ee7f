"""The old import path of the damper-controller node: it lives in the package :mod:`susp_sim_ros.ros`
(:mod:`susp_sim_ros.ros.controller_node`, entry point ``susp_damper_controller =
susp_sim_ros.ros.controller_node:main``). Kept so that console scripts installed before the move and
``python -m susp_sim_ros.controller_node`` keep working; new code imports from :mod:`susp_sim_ros.ros`."""
from __future__ import annotations

import sys

from .ros.controller_node import NODE_NAME, DamperControllerNode, main

__all__ = ["NODE_NAME", "DamperControllerNode", "main"]

if __name__ == "__main__":
    sys.exit(main())
