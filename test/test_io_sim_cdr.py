"""The node's fast ``/sim`` encoders (:mod:`susp_sim_ros.io.sim_cdr`): for any output vector and time they
give the message the builders of :mod:`susp_sim_ros.io.messages` give, read by our decoder, by rclpy's
deserialiser and by rosbags."""
from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from susp_sim_ros.io import messages as M
from susp_sim_ros.io.sim_cdr import imu_cdr, odom_cdr, suspension_cdr
from susp_sim_ros.model.layout import OUTPUT_LABELS, output_index

finite = st.floats(allow_nan=False, allow_infinity=False, width=64)
vectors = st.lists(finite, min_size=len(OUTPUT_LABELS), max_size=len(OUTPUT_LABELS)).map(np.array)
times = st.integers(min_value=0, max_value=2**31 * 1_000_000_000 - 1)

ENCODED = [(M.IMU, lambda t, y: imu_cdr(t, y), lambda t, y: M.imu_msg(t, y)),
           (M.ODOMETRY, odom_cdr, M.odom_msg),
           (M.FLOAT64_ARRAY, lambda t, y: suspension_cdr(y), lambda t, y: M.suspension_msg(y))]


@pytest.mark.parametrize("msgtype,fast,builder", ENCODED, ids=[m for m, _, _ in ENCODED])
@settings(max_examples=60, deadline=None)
@given(t=times, y=vectors)
def test_fast_encoder_gives_the_builders_message(msgtype, fast, builder, t, y):
    assert M.decode(msgtype, fast(t, y)) == M.decode(msgtype, M.encode(msgtype, builder(t, y)))


def test_frame_id_and_layout_as_rclpy_reads_them():
    rclpy_ser = pytest.importorskip("rclpy.serialization")
    from nav_msgs.msg import Odometry
    from sensor_msgs.msg import Imu
    from std_msgs.msg import Float64MultiArray
    y = np.linspace(-1.0, 1.0, len(OUTPUT_LABELS))
    imu = rclpy_ser.deserialize_message(imu_cdr(3_000_000_007, y, frame_id="imu_link"), Imu)
    assert (imu.header.stamp.sec, imu.header.stamp.nanosec, imu.header.frame_id) == (3, 7, "imu_link")
    odom = rclpy_ser.deserialize_message(odom_cdr(5, y), Odometry)
    assert (odom.header.frame_id, odom.child_frame_id) == ("odom", "base_link")
    assert len(odom.pose.covariance) == 36 and odom.pose.pose.orientation.w == pytest.approx(
        np.cos(y[output_index("YAW")] / 2), abs=1e-15)
    susp = rclpy_ser.deserialize_message(suspension_cdr(y), Float64MultiArray)
    assert [(d.label, d.size, d.stride) for d in susp.layout.dim] == [("wheel", 4, 36), ("quantity", 9, 9)]
    np.testing.assert_array_equal(susp.data, y[M.SUSPENSION_COLUMNS])


def test_rosbags_reads_them():
    from rosbags.typesys import Stores, get_typestore
    ts = get_typestore(Stores.ROS2_JAZZY)
    y = np.arange(len(OUTPUT_LABELS), dtype=float)
    imu = ts.deserialize_cdr(imu_cdr(1_250_000_000, y), M.IMU)
    assert (imu.header.stamp.sec, imu.header.stamp.nanosec) == (1, 250_000_000)
    assert imu.angular_velocity.z == y[output_index("YAW_RATE")]
    odom = ts.deserialize_cdr(odom_cdr(0, y), M.ODOMETRY)
    assert odom.twist.twist.linear.x == y[output_index("VEL_X")]
