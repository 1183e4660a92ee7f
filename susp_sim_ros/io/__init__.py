"""MCAP input/output in the ROS 2 profile (no rclpy): message definitions, recorder, test drives, topic maps."""
from .drive import ImuSeries, Series, TestDrive, read_drive, read_imu, write_drive
from .recorder import McapRecorder
from .topic_map import TopicMap, add_topic_map_argument, load_topic_map

__all__ = ["ImuSeries", "Series", "TestDrive", "read_drive", "read_imu", "write_drive", "McapRecorder",
           "TopicMap", "add_topic_map_argument", "load_topic_map"]
