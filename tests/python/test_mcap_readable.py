"""A reader we did not write accepts our bags.

Writes a bag with one message of every supported type through the Rust example
`write_sample_bag` (values in crates/ekf-cli/examples/write_sample_bag/sample.rs) and reads it
back with the `mcap` and `mcap-ros2-support` Python packages, which decode CDR from the
ros2msg schema text stored in the file. A schema text that does not match our structs, or a
misaligned field, shows up here as a decode error or a wrong value.

Run: cargo build -p ekf-cli --bins --examples &&
pip install -r tests/python/requirements.txt && python -m pytest tests/python
"""

import math
import subprocess

import pytest
from mcap.reader import make_reader
from mcap_ros2.reader import read_ros2_messages

STAMP_NS = 100 * 10**9 + 250


@pytest.fixture(scope="module")
def bag(tmp_path_factory, sample_bag_writer):
    out = tmp_path_factory.mktemp("bag") / "sample.mcap"
    subprocess.run([str(sample_bag_writer), str(out)], check=True)
    return out


@pytest.fixture(scope="module")
def messages(bag):
    return {m.channel.topic: m for m in read_ros2_messages(str(bag))}


def yaw(q):
    return math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z))


def cov(offset, n):
    return [k + offset for k in range(n)]


def test_file_is_a_ros2_bag_with_summary(bag):
    with open(bag, "rb") as f:
        reader = make_reader(f)
        assert reader.get_header().profile == "ros2"
        summary = reader.get_summary()
        assert summary is not None and summary.statistics.message_count == 26
        assert len(summary.chunk_indexes) >= 1
        for channel in summary.channels.values():
            assert channel.message_encoding == "cdr"
            assert summary.schemas[channel.schema_id].encoding == "ros2msg"
            assert channel.metadata["offered_qos_profiles"] == "[]"


def test_every_topic_decodes_with_its_type(messages):
    assert len(messages) == 26
    assert messages["/scan"].schema.name == "sensor_msgs/msg/LaserScan"
    assert messages["/odom"].schema.name == "nav_msgs/msg/Odometry"
    for i, m in enumerate(sorted(messages.values(), key=lambda m: m.log_time_ns)):
        assert m.log_time_ns == STAMP_NS + i * 1000
        assert m.publish_time_ns == m.log_time_ns


def test_laser_scan(messages):
    scan = messages["/scan"].ros_msg
    assert scan.header.stamp.sec == 100 and scan.header.stamp.nanosec == 250
    assert scan.header.frame_id == "laser"
    assert (scan.angle_min, scan.angle_max, scan.angle_increment) == (-1.5, 1.5, 1.5)
    assert scan.scan_time == pytest.approx(0.2)
    assert scan.range_max == 8.0
    assert list(scan.ranges) == [1.0, 2.0, 4.0]
    assert list(scan.intensities) == [10.0, 20.0, 30.0]


def test_odometry_and_covariances(messages):
    odom = messages["/odom"].ros_msg
    assert odom.child_frame_id == "base_link"
    assert odom.pose.pose.position.x == 1.5 and odom.pose.pose.position.y == -2.5
    assert yaw(odom.pose.pose.orientation) == pytest.approx(0.5)
    assert list(odom.pose.covariance) == cov(0.0, 36)
    assert odom.twist.twist.angular.z == -0.3
    assert list(odom.twist.covariance) == cov(1000.0, 36)
    pwcs = messages["/sample/pose_with_covariance_stamped"].ros_msg
    assert list(pwcs.pose.covariance) == cov(100.0, 36)


def test_joint_state(messages):
    js = messages["/joint_states"].ros_msg
    assert js.header.frame_id == ""
    assert list(js.name) == ["wheel_left", "wheel_right"]
    assert list(js.position) == [0.1, 0.2]
    assert list(js.velocity) == [3.0, 3.5]
    assert list(js.effort) == []


def test_compass_sources(messages):
    imu = messages["/compass"].ros_msg
    assert yaw(imu.orientation) == pytest.approx(1.25)
    assert list(imu.orientation_covariance) == cov(0.0, 9)
    assert list(imu.linear_acceleration_covariance) == cov(20.0, 9)
    mag = messages["/magnetic_field"].ros_msg
    assert (mag.magnetic_field.x, mag.magnetic_field.z) == (2.0e-5, 4.0e-5)
    assert list(mag.magnetic_field_covariance) == cov(1.0, 9)


def test_gps(messages):
    fix = messages["/fix"].ros_msg
    assert fix.status.status == -1 and fix.status.service == 2
    assert (fix.latitude, fix.longitude, fix.altitude) == (48.1, 11.6, 520.5)
    assert list(fix.position_covariance) == cov(2.0, 9)
    assert fix.position_covariance_type == 2
    status = messages["/sample/nav_sat_status"].ros_msg
    assert (status.status, status.service) == (1, 9)


def test_tf(messages):
    tf = messages["/tf"].ros_msg
    assert len(tf.transforms) == 2
    t = tf.transforms[0]
    assert (t.header.frame_id, t.child_frame_id) == ("map", "odom")
    assert (t.transform.translation.x, t.transform.translation.y) == (3.0, 4.0)
    assert yaw(t.transform.rotation) == pytest.approx(-1.0)
    assert tf.transforms[1].transform.rotation.w == 1.0


def check_marker(m):
    assert (m.ns, m.id, m.type, m.action) == ("lines", 7, 5, 0)
    assert m.scale.x == 0.05
    assert (m.color.r, m.color.g, m.color.a) == (1.0, 0.5, 1.0)
    assert (m.lifetime.sec, m.lifetime.nanosec) == (2, 500)
    assert m.frame_locked is True
    assert [(p.x, p.y) for p in m.points] == [(0.0, 0.0), (1.0, 2.0)]
    assert [(c.g, c.a) for c in m.colors] == [(1.0, 0.5)]
    assert m.texture_resource == "embedded://tex"
    assert m.texture.header.frame_id == "cam" and m.texture.format == "png"
    assert bytes(m.texture.data) == b"\x89PNG"
    assert [(uv.u, uv.v) for uv in m.uv_coordinates] == [(0.25, 0.75)]
    assert m.text == "wall 3"
    assert m.mesh_resource == "embedded://mesh"
    assert m.mesh_file.filename == "m.stl" and bytes(m.mesh_file.data) == b"\x01\x02\x03"
    assert m.mesh_use_embedded_materials is True


def test_markers(messages):
    check_marker(messages["/sample/marker"].ros_msg)
    array = messages["/ekf/lines"].ros_msg
    assert len(array.markers) == 2
    check_marker(array.markers[0])
    assert array.markers[1].ns == "" and array.markers[1].mesh_use_embedded_materials is False


def test_diagnostics(messages):
    diag = messages["/diagnostics"].ros_msg
    (status,) = diag.status
    assert (status.level, status.name, status.hardware_id) == (1, "ekf: laser", "lms221")
    assert status.message == "2 lines gated out"
    assert [(kv.key, kv.value) for kv in status.values] == [("matched", "4"), ("gated", "2")]
    kv = messages["/sample/key_value"].ros_msg
    assert (kv.key, kv.value) == ("k", "v")


def test_small_geometry_types(messages):
    assert messages["/sample/time"].ros_msg.nanosec == 250
    assert messages["/sample/header"].ros_msg.frame_id == "base_link"
    assert messages["/sample/point"].ros_msg.z == 0.25
    assert yaw(messages["/sample/quaternion"].ros_msg) == pytest.approx(0.5)
    assert messages["/sample/vector3"].ros_msg.z == -0.3
    assert messages["/sample/pose"].ros_msg.position.y == -2.5
    assert messages["/sample/pose_stamped"].ros_msg.header.frame_id == "map"
    assert list(messages["/sample/pose_with_covariance"].ros_msg.covariance) == cov(0.5, 36)
    assert messages["/sample/twist"].ros_msg.linear.x == 0.4
    twc = messages["/sample/twist_with_covariance"].ros_msg
    assert list(twc.covariance) == cov(-36.0, 36)
    assert messages["/sample/transform"].ros_msg.translation.y == 4.0
    assert messages["/sample/transform_stamped"].ros_msg.child_frame_id == "odom"
