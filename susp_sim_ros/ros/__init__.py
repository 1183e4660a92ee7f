"""The ROS 2 shell around :class:`~susp_sim_ros.runtime.sim_core.SimCore` (with ``susp replay`` the only code
importing rclpy).

- :mod:`.node`: ``SuspSimNode`` and the ``susp_sim_node`` entry point ``main``;
- :mod:`.controller_node`: ``DamperControllerNode``, the ``susp_damper_controller`` entry point;
- :mod:`.run`: :func:`~.run.run_node`, the entry points' common init/spin/shutdown and exit codes;
- :mod:`.inputs`: the subscription callbacks and when an input takes effect (wall time, sim time);
- :mod:`.parameters`: the node's parameters with their ``ParameterDescriptor`` (read-only, ranges) and the
  validation of run-time changes;
- :mod:`.sim_time`: :class:`~.sim_time.SimTimeOrderer`, the pure sim-time reorder queue (no rclpy);
- :mod:`.timing`: real-time scheduling, the wall-time tick thread and its timing statistics;
- :mod:`.recording`: the recording queue off the real-time path;
- :mod:`.conversion`: plain-dict messages (:mod:`~susp_sim_ros.io.messages`) to and from rclpy objects;
- :mod:`.status`: the ``/diagnostics`` statuses; :mod:`.qos`: the topics' quality of service;
- :mod:`.rclpy_workarounds`: the one place that uses rclpy below its documented Python API, and why.

Nothing is imported here, so :mod:`.sim_time` stays importable without rclpy.
"""
