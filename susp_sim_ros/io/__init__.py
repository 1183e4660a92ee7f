"""MCAP input/output in the ROS 2 profile (no rclpy): message definitions, recorder, test drives."""
from .drive import ImuSeries, Series, TestDrive, read_drive, read_imu, write_drive
from .recorder import McapRecorder

__all__ = ["ImuSeries", "Series", "TestDrive", "read_drive", "read_imu", "write_drive", "McapRecorder"]
