"""susp_sim_ros: five-mass full-vehicle model with phenomenological suspension friction for ROS 2.

Layers (imports go one way only): ``model`` (physics, numpy/numba) <- ``io`` and ``analysis`` (MCAP,
validation, discrepancy; no rclpy) <- ``node`` and ``cli`` (shells).
"""
__version__ = "0.1.0"
