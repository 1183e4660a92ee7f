"""The runtime shared by the ROS 2 node and the offline runner (pure; no rclpy).

- :mod:`.sim_core`: ``SimCore``, which holds and validates the inputs and steps the compiled model;
- :mod:`.lockstep`: ``run_lockstep`` / ``maneuver_drive``, a recorded drive through ``SimCore`` without DDS.
"""
