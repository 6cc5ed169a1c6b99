"""Readers we did not write accept what the `ekf` command writes from real robot logs.

`ekf import mrpt`, `ekf import carmen` and `ekf replay` run on the bundled logs in
shared/data (see conftest.py); their bags are decoded with `mcap` + `mcap-ros2-support` and,
independently, with `rosbags` (its own CDR decoder, fed by the ros2msg schemas in the file),
and the values are compared with the source text logs and with each other.

Run: scripts/test-all.sh, or cargo build -p ekf-cli --bins --examples &&
pip install -r tests/python/requirements.txt && python -m pytest tests/python
(EKF_BIN overrides target/debug/ekf).
"""

import dataclasses
import gzip
import math
import struct
from collections import Counter
from decimal import Decimal
from pathlib import Path

import pytest
from mcap.reader import make_reader
from mcap_ros2.reader import read_ros2_messages

from conftest import CARMEN_LOG, MRPT_LOG

LASER_SCAN = "sensor_msgs/msg/LaserScan"
ODOMETRY = "nav_msgs/msg/Odometry"
TF_MESSAGE = "tf2_msgs/msg/TFMessage"
IMU = "sensor_msgs/msg/Imu"
POSE_COV_STAMPED = "geometry_msgs/msg/PoseWithCovarianceStamped"
MARKER_ARRAY = "visualization_msgs/msg/MarkerArray"
DIAGNOSTIC_ARRAY = "diagnostic_msgs/msg/DiagnosticArray"
LINE_STRIP, LINE_LIST = 4, 5
XY_YAW = (0, 1, 5)  # rows/columns of x, y and yaw in a ROS 6x6 covariance


# ---------------------------------------------------------------------------- helpers


def decode(path):
    """Every message of the bag, decoded by mcap-ros2-support, as {topic: [message]}.

    read_ros2_messages raises on the first message it cannot decode, so a complete list
    means every message decoded.
    """
    by_topic = {}
    for m in read_ros2_messages(str(path)):
        by_topic.setdefault(m.channel.topic, []).append(m)
    return by_topic


def with_messages(outputs):
    """The outputs of an `ekf` run (the bag path first) and, last, the bag's messages by topic."""
    return (*outputs, decode(outputs[0]))


def types_and_counts(by_topic):
    return {t: (ms[0].schema.name, len(ms)) for t, ms in by_topic.items()}


def stamp_ns(header):
    return header.stamp.sec * 10**9 + header.stamp.nanosec


def seconds_to_ns(text):
    """Decimal seconds from a log line to integer nanoseconds, exactly."""
    return int(Decimal(text) * 10**9)


def yaw(q):
    return math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z))


def angle_diff(a, b):
    return math.remainder(a - b, math.tau)


def assert_planar_unit_quaternion(q):
    assert q.x == 0.0 and q.y == 0.0
    assert q.z * q.z + q.w * q.w == pytest.approx(1.0, abs=1e-12)


def f32(x):
    """The value a float32 field holds for the decimal x, as a Python float."""
    return struct.unpack("<f", struct.pack("<f", x))[0]


def check_bag_file(path, expected_messages):
    """MCAP with the ros2 profile, a summary, CDR channels and ros2msg schemas."""
    with open(path, "rb") as f:
        reader = make_reader(f)
        assert reader.get_header().profile == "ros2"
        summary = reader.get_summary()
        assert summary is not None
        assert summary.statistics.message_count == expected_messages
        for channel in summary.channels.values():
            assert channel.message_encoding == "cdr"
            assert summary.schemas[channel.schema_id].encoding == "ros2msg"
        return summary


def check_log_times_are_header_stamps(by_topic):
    """Every message is logged at its header stamp (the first transform's or marker's for
    TFMessage and MarkerArray), and the bag's messages come in time order."""
    for topic, ms in by_topic.items():
        for m in ms:
            msg = m.ros_msg
            if hasattr(msg, "transforms"):
                header = msg.transforms[0].header
            elif hasattr(msg, "markers"):
                header = msg.markers[0].header
                assert all(stamp_ns(k.header) == stamp_ns(header) for k in msg.markers)
            else:
                header = msg.header
            assert m.log_time_ns == stamp_ns(header), topic
        times = [m.log_time_ns for m in ms]
        assert times == sorted(times), topic


# ----------------------------------------------------------------------- source logs


@pytest.fixture(scope="module")
def mrpt_source(shared_data):
    """(scans, odometry) parsed from the MRPT text log: scans as (stamp_ns, header
    fields, ranges), odometry as (stamp_ns, x, y, theta)."""
    scans, odom = [], []
    for line in (shared_data / MRPT_LOG).read_text().splitlines():
        f = line.split()
        if f and f[0] == "RAWSCAN":
            n = int(f[2])
            scans.append((seconds_to_ns(f[1]), [float(v) for v in f[3:8]],
                          [float(v) for v in f[8:8 + n]]))
            assert f[8 + n:] == ["label=", "rightToLeft=1"]  # beams counter-clockwise
        elif f and f[0] == "ODOM":
            odom.append((seconds_to_ns(f[7]), float(f[1]), float(f[2]), float(f[3])))
    return scans, odom


@pytest.fixture(scope="module")
def carmen_scans(shared_data):
    """FLASER records of the ACES log: (stamp_ns, ranges, x, y, theta)."""
    scans = []
    with gzip.open(shared_data / CARMEN_LOG, "rt") as f:
        for line in f:
            fields = line.split()
            if fields and fields[0] == "FLASER":
                n = int(fields[1])
                ranges = [float(v) for v in fields[2:2 + n]]
                x, y, theta = (float(v) for v in fields[2 + n:5 + n])
                scans.append((seconds_to_ns(fields[8 + n]), ranges, x, y, theta))
    return scans


# ----------------------------------------------------------------------- ekf import mrpt


@pytest.fixture(scope="module")
def mrpt(mrpt_import):
    return with_messages(mrpt_import)


def test_mrpt_bag_structure(mrpt):
    bag, summary, by_topic = mrpt
    assert summary["messages_written"] == 450
    check_bag_file(bag, 450)
    assert types_and_counts(by_topic) == {
        "/scan": (LASER_SCAN, 225),
        "/odom": (ODOMETRY, 224),
        "/tf_static": (TF_MESSAGE, 1),
    }
    check_log_times_are_header_stamps(by_topic)
    times = [m.log_time_ns for ms in by_topic.values() for m in ms]
    assert (min(times), max(times)) == (summary["stats"]["t_min_ns"],
                                        summary["stats"]["t_max_ns"])


def test_mrpt_scans_match_the_log(mrpt, mrpt_source):
    _, _, by_topic = mrpt
    scans, _ = mrpt_source
    assert len(scans) == len(by_topic["/scan"]) == 225
    for m, (t_ns, (aperture, max_range, sx, sy, stheta), ranges) in zip(by_topic["/scan"], scans):
        s = m.ros_msg
        assert s.header.frame_id == "laser"
        assert stamp_ns(s.header) == t_ns
        assert len(s.ranges) == 361
        assert s.angle_min == pytest.approx(-math.pi / 2, abs=1e-6)
        assert s.angle_max == pytest.approx(math.pi / 2, abs=1e-6)
        assert s.angle_increment == pytest.approx(math.pi / 360, rel=1e-6)
        assert s.angle_min + 360 * s.angle_increment == pytest.approx(s.angle_max, abs=1e-5)
        assert s.range_max == max_range == 80.0
        assert list(s.ranges) == [f32(r) for r in ranges]
        assert (sx, sy, stheta) == (0.78, 0.0, 0.0)
        assert aperture == pytest.approx(math.pi, abs=1e-6)


def test_mrpt_odometry_matches_the_log(mrpt, mrpt_source):
    _, _, by_topic = mrpt
    _, odom = mrpt_source
    assert len(odom) == len(by_topic["/odom"]) == 224
    for m, (t_ns, x, y, theta) in zip(by_topic["/odom"], odom):
        o = m.ros_msg
        assert (o.header.frame_id, o.child_frame_id) == ("odom", "base_link")
        assert stamp_ns(o.header) == t_ns
        p = o.pose.pose
        assert (p.position.x, p.position.y, p.position.z) == (x, y, 0.0)
        assert_planar_unit_quaternion(p.orientation)
        assert angle_diff(yaw(p.orientation), theta) == pytest.approx(0.0, abs=1e-12)


def test_mrpt_laser_mount_in_tf_static(mrpt):
    _, _, by_topic = mrpt
    (tf,) = by_topic["/tf_static"]
    (t,) = tf.ros_msg.transforms
    assert (t.header.frame_id, t.child_frame_id) == ("base_link", "laser")
    tr = t.transform.translation
    assert (tr.x, tr.y, tr.z) == (0.78, 0.0, 0.0)
    r = t.transform.rotation
    assert (r.x, r.y, r.z, r.w) == (0.0, 0.0, 0.0, 1.0)


# --------------------------------------------------------------------- ekf import carmen


@pytest.fixture(scope="module")
def carmen(carmen_import):
    return with_messages(carmen_import)


def test_carmen_bag_structure(carmen):
    bag, summary, by_topic = carmen
    stats = summary["stats"]
    assert (stats["scans"], stats["references"], stats["compass"]) == (440, 440, 440)
    assert stats["odometry"] == 7814 - 440  # the 440 resets to the corrected pose are dropped
    check_bag_file(bag, summary["messages_written"])
    assert types_and_counts(by_topic) == {
        "/scan": (LASER_SCAN, 440),
        "/ground_truth": (ODOMETRY, 440),
        "/compass": (IMU, 440),
        "/odom": (ODOMETRY, 7374),
        "/tf_static": (TF_MESSAGE, 1),
    }
    assert sum(map(len, by_topic.values())) == summary["messages_written"]
    check_log_times_are_header_stamps(by_topic)


def test_carmen_synthetic_compass_metadata(carmen):
    bag, _, _ = carmen
    with open(bag, "rb") as f:
        reader = make_reader(f)
        records = {m.name: m.metadata for m in reader.iter_metadata()}
        assert reader.get_summary().statistics.metadata_count == 1
    md = records["synthetic_compass"]
    assert (md["topic"], md["sigma_deg"], md["seed"]) == ("/compass", "2", "1")
    assert "SYNTHETIC" in md["description"]


def test_carmen_scans_and_reference_match_the_log(carmen, carmen_scans):
    _, _, by_topic = carmen
    assert len(carmen_scans) == 440
    triples = zip(by_topic["/scan"], by_topic["/ground_truth"], carmen_scans)
    for scan_m, truth_m, (t_ns, ranges, x, y, theta) in triples:
        s = scan_m.ros_msg
        assert s.header.frame_id == "laser" and stamp_ns(s.header) == t_ns
        assert len(s.ranges) == 180
        assert s.angle_min == pytest.approx(-math.pi / 2, abs=1e-6)
        assert s.angle_increment == pytest.approx(math.radians(1), rel=1e-6)
        assert s.range_max == pytest.approx(49.5, rel=1e-6)  # saturation at 50 m, less 1 %
        assert list(s.ranges) == [f32(r) for r in ranges]
        g = truth_m.ros_msg
        assert (g.header.frame_id, g.child_frame_id) == ("map", "base_link")
        assert stamp_ns(g.header) == t_ns
        assert (g.pose.pose.position.x, g.pose.pose.position.y) == (x, y)
        assert_planar_unit_quaternion(g.pose.pose.orientation)
        assert angle_diff(yaw(g.pose.pose.orientation), theta) == pytest.approx(0.0, abs=1e-12)


def test_carmen_synthetic_compass_is_truth_plus_2_degrees_noise(carmen):
    _, _, by_topic = carmen
    errors = []
    for c, g in zip(by_topic["/compass"], by_topic["/ground_truth"]):
        imu = c.ros_msg
        assert imu.header.frame_id == "base_link"
        assert stamp_ns(imu.header) == stamp_ns(g.ros_msg.header)
        assert_planar_unit_quaternion(imu.orientation)
        assert list(imu.orientation_covariance[:8]) == [0.0] * 8
        assert imu.orientation_covariance[8] == pytest.approx(math.radians(2) ** 2, rel=1e-12)
        # REP 145: a covariance starting with -1 marks a field as not provided.
        assert imu.angular_velocity_covariance[0] == -1.0
        assert imu.linear_acceleration_covariance[0] == -1.0
        errors.append(math.degrees(angle_diff(yaw(imu.orientation),
                                              yaw(g.ros_msg.pose.pose.orientation))))
    assert len(errors) == 440
    rms = math.sqrt(sum(e * e for e in errors) / len(errors))
    mean = sum(errors) / len(errors)
    # N(0, 2°) over 440 samples: the sample RMS is within 2° ± 0.35° (> 5 standard errors).
    assert 1.65 < rms < 2.35
    assert abs(mean) < 0.5
    assert max(map(abs, errors)) < 10.0


# ---------------------------------------------------------------------------- ekf replay


@pytest.fixture(scope="module")
def replayed(replay):
    return with_messages(replay)


def test_replay_bag_structure(replayed):
    bag, _, summary, by_topic = replayed
    lines, compass = summary["lines"], summary["compass"]
    compass_updates = compass["accepted"] + compass["rejected"]
    assert summary["mode"] == "laser+compass"
    assert lines["scans"] == lines["scans_used"] == 440
    assert compass_updates == 440
    expected = {
        # a pose after every motion step, every scan and every compass update
        "/ekf/pose": (POSE_COV_STAMPED,
                      summary["motion_steps"] + lines["scans_used"] + compass_updates),
        "/ekf/markers": (MARKER_ARRAY, lines["scans_used"]),
        "/ekf/map": (MARKER_ARRAY, 1),
        "/ekf/diagnostics": (DIAGNOSTIC_ARRAY, lines["scans_used"] + compass_updates),
    }
    assert types_and_counts(by_topic) == expected
    check_bag_file(bag, sum(n for _, n in expected.values()))
    check_log_times_are_header_stamps(by_topic)


def test_replay_pose_covariance(replayed):
    _, _, _, by_topic = replayed
    for m in by_topic["/ekf/pose"]:
        msg = m.ros_msg
        assert msg.header.frame_id == "map"
        assert msg.pose.pose.position.z == 0.0
        assert_planar_unit_quaternion(msg.pose.pose.orientation)
        c = list(msg.pose.covariance)
        assert len(c) == 36
        scale = max(abs(c[i * 7]) for i in XY_YAW)
        for i in range(6):
            for j in range(6):
                if i in XY_YAW and j in XY_YAW:
                    assert c[i * 6 + j] == pytest.approx(c[j * 6 + i], abs=1e-12 * scale)
                else:  # z, roll and pitch are not estimated
                    assert c[i * 6 + j] == 0.0
        # positive definite: the leading minors of the x/y/yaw block are positive
        p = [[c[i * 6 + j] for j in XY_YAW] for i in XY_YAW]
        m2 = p[0][0] * p[1][1] - p[0][1] * p[1][0]
        m3 = (p[0][0] * (p[1][1] * p[2][2] - p[1][2] * p[2][1])
              - p[0][1] * (p[1][0] * p[2][2] - p[1][2] * p[2][0])
              + p[0][2] * (p[1][0] * p[2][1] - p[1][1] * p[2][0]))
        assert p[0][0] > 0 and m2 > 0 and m3 > 0


def test_replay_markers(replayed, carmen):
    _, _, summary, by_topic = replayed
    scan_times = [m.log_time_ns for m in carmen[2]["/scan"]]
    assert [m.log_time_ns for m in by_topic["/ekf/markers"]] == scan_times
    for m in by_topic["/ekf/markers"]:
        markers = m.ros_msg.markers
        assert [(k.ns, k.type) for k in markers] == [
            ("extracted", LINE_LIST), ("matched", LINE_LIST), ("covariance_2sigma", LINE_STRIP)]
        for k in markers:
            assert k.header.frame_id == "map" and k.action == 0
        assert len(markers[0].points) % 2 == 0 and len(markers[1].points) % 2 == 0
        assert len(markers[1].points) <= len(markers[0].points)
        ellipse = markers[2].points
        assert len(ellipse) == 37
        assert (ellipse[0].x, ellipse[0].y) == pytest.approx((ellipse[-1].x, ellipse[-1].y))
    (map_msg,) = by_topic["/ekf/map"]
    (marker,) = map_msg.ros_msg.markers
    assert (marker.ns, marker.type, marker.header.frame_id) == ("map", LINE_LIST, "map")
    assert summary["map"] == "first scan"
    assert len(marker.points) == 2 * summary["map_segments"] > 0


def test_replay_diagnostics(replayed):
    _, _, summary, by_topic = replayed
    names = Counter()
    fused = compass_fused = 0
    for m in by_topic["/ekf/diagnostics"]:
        (status,) = m.ros_msg.status
        names[status.name] += 1
        assert status.hardware_id == "ekf" and status.level in (0, 1)
        values = {kv.key: kv.value for kv in status.values}
        if status.name == "ekf/scan":
            assert list(values) == ["lines_extracted", "lines_matched", "lines_rejected",
                                    "lines_fused", "lines_refused", "lines_merged", "walls_refitted",
                                    "nis",
                                    "rejections"]
            assert len([r for r in values["rejections"].split("; ") if r]) == int(
                values["lines_rejected"])
            fused += int(values["lines_fused"])
        else:
            assert status.name == "ekf/compass"
            assert list(values) == ["nis", "heading_rad", "rejected_in_a_row"]
            fused_here = status.message.startswith("fused")
            # Through the gate (level 0, none rejected), or ending a lock-out (level 1).
            assert (status.level == 0) == (fused_here and values["rejected_in_a_row"] == "0")
            compass_fused += fused_here
    assert names == {"ekf/scan": 440, "ekf/compass": 440}
    assert fused == summary["lines"]["fused"]
    assert compass_fused == summary["compass"]["accepted"]


def test_replay_tum_trajectory(replayed):
    _, tum, summary, by_topic = replayed
    rows = [line.split() for line in Path(tum).read_text().splitlines()
            if line.strip() and not line.startswith("#")]
    assert len(rows) == summary["poses_written"] > 0
    assert all(len(r) == 8 for r in rows)
    stamps = [seconds_to_ns(r[0]) for r in rows]
    assert all(a < b for a, b in zip(stamps, stamps[1:]))
    poses_at = {}
    for m in by_topic["/ekf/pose"]:
        p = m.ros_msg.pose.pose
        poses_at.setdefault(m.log_time_ns, []).append(
            (p.position.x, p.position.y, p.orientation.z, p.orientation.w))
    for t_ns, r in zip(stamps, rows):
        x, y, tz, qx, qy, qz, qw = map(float, r[1:])
        assert (tz, qx, qy) == (0.0, 0.0, 0.0)
        assert math.sqrt(qx * qx + qy * qy + qz * qz + qw * qw) == pytest.approx(1.0, abs=1e-9)
        # the TUM row is one of the poses the bag holds at that time
        assert any(pytest.approx((x, y, qz, qw), abs=1e-9) == q for q in poses_at[t_ns])


# ------------------------------------------------------- second reader: rosbags AnyReader


def plain(value):
    """A decoded message as nested dicts/lists, whichever library decoded it."""
    if isinstance(value, (bool, int, float, str)):
        return value
    if isinstance(value, (bytes, bytearray)):
        return list(value)
    if hasattr(value, "tolist"):  # numpy arrays (rosbags)
        return value.tolist()
    if isinstance(value, (list, tuple)):
        return [plain(v) for v in value]
    if dataclasses.is_dataclass(value):  # rosbags
        # its fields also hold the message's constants (upper case, e.g. Marker.LINE_LIST),
        # which mcap-ros2-support leaves out
        return {f.name: plain(getattr(value, f.name)) for f in dataclasses.fields(value)
                if f.name != "__msgtype__" and not f.name.isupper()}
    if hasattr(value, "__slots__"):  # mcap-ros2-support
        return {k: plain(getattr(value, k)) for k in value.__slots__}
    raise TypeError(f"cannot compare a {type(value)}")


@pytest.mark.parametrize("which", ["mrpt", "carmen", "replayed"])
def test_rosbags_decodes_the_same_values(which, request):
    from rosbags.highlevel import AnyReader

    bag, by_topic = request.getfixturevalue(which)[0], request.getfixturevalue(which)[-1]
    expected = {t: [(m.log_time_ns, plain(m.ros_msg)) for m in ms] for t, ms in by_topic.items()}
    got = {}
    with AnyReader([Path(bag)]) as reader:
        assert {c.topic: c.msgtype for c in reader.connections} == {
            t: ms[0].schema.name for t, ms in by_topic.items()}
        for conn, t_ns, raw in reader.messages():
            got.setdefault(conn.topic, []).append(
                (t_ns, plain(reader.deserialize(raw, conn.msgtype))))
    assert got.keys() == expected.keys()
    for topic in expected:
        assert len(got[topic]) == len(expected[topic]), topic
        assert got[topic] == expected[topic], topic
