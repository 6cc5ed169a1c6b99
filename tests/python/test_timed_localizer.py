"""ekf_loc.TimedLocalizer: the time-ordered loop `ekf replay` drives, fed by hand.

The bundled simulated bag's wheel readings and scans, pushed in log order, give exactly
the trajectory `ekf_loc.replay` gives for the bag; pushed with the scans arriving late
(within the lag) they give it too; later than the lag they are dropped and counted.
"""

from pathlib import Path

import numpy as np
import pytest
from mcap_ros2.reader import read_ros2_messages

import ekf_loc

BAG = Path(__file__).resolve().parents[2] / "testdata" / "sim-paper.mcap"
# The scan frame's mount in the bag's /tf_static, which replay reads.
CONFIG = {"laser_mount": {"x": 0.2, "y": 0.0, "theta": 0.0}}
P0 = np.diag([0.05**2, 0.05**2, 0.02**2])  # `ekf config` [initial] sigmas


def stamp(msg) -> int:
    return msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec


def bag_inputs():
    """(stamp_ns, kind, payload) for the joint states and scans, in log order."""
    out = []
    for m in read_ros2_messages(str(BAG), topics=["/joint_states", "/scan"]):
        msg = m.ros_msg
        if m.channel.topic == "/joint_states":
            i = list(msg.name).index("left_wheel_joint")
            j = list(msg.name).index("right_wheel_joint")
            out.append((stamp(msg), "wheels", (msg.position[i], msg.position[j])))
        else:
            scan = (
                np.asarray(msg.ranges, dtype=np.float32),
                msg.angle_min,
                msg.angle_increment,
                msg.range_min,
                msg.range_max,
            )
            out.append((stamp(msg), "scan", scan))
    return out


def feed(loc, inputs):
    kept = []
    for t, kind, payload in inputs:
        if kind == "wheels":
            kept.append(loc.add_wheel_angles(t, *payload))
        else:
            ranges, amin, ainc, rmin, rmax = payload
            kept.append(loc.add_scan(t, ranges, amin, ainc, rmin, rmax))
    loc.flush()
    return kept


def last_per_stamp(t, states):
    """One state per stamp, the last, as the TUM trajectory keeps it."""
    keep = np.append(t[1:] != t[:-1], True)
    return t[keep], states[keep]


@pytest.fixture(scope="module")
def inputs():
    return bag_inputs()


@pytest.fixture(scope="module")
def replayed():
    return ekf_loc.replay(BAG, mode="laser")


def new_localizer(**kwargs):
    return ekf_loc.TimedLocalizer([0.0, 0.0, 0.0], P0, config=CONFIG, mode="laser", **kwargs)


def test_fed_by_hand_it_gives_the_replay_of_the_bag_exactly(inputs, replayed):
    loc = new_localizer()
    assert loc.pose_now() is None, "nothing fused yet"
    assert all(feed(loc, inputs))
    t, states, covs = loc.take_trajectory()
    assert states.shape == (len(t), 3) and covs.shape == (len(t), 3, 3)
    t, states = last_per_stamp(t, states)
    np.testing.assert_array_equal(t, replayed.t_ns)
    np.testing.assert_array_equal(states[:, 0], replayed.x)
    np.testing.assert_array_equal(states[:, 1], replayed.y)
    np.testing.assert_array_equal(states[:, 2], replayed.theta)
    counts = loc.counts()
    lines = replayed.summary["lines"]
    assert counts["lines"] == lines
    assert counts["motion_steps"] == replayed.summary["motion_steps"]
    assert counts["too_late"] == 0
    assert loc.take_trajectory()[0].size == 0, "taken"


def with_late_scans(inputs, delay_ns):
    arrival = [(t + delay_ns if kind == "scan" else t, k) for k, (t, kind, _) in enumerate(inputs)]
    return [inputs[k] for _, k in sorted(arrival)]


def test_scans_up_to_the_lag_late_are_fused_at_their_stamps(inputs, replayed):
    loc = new_localizer()
    assert all(feed(loc, with_late_scans(inputs, 450_000_000)))
    t, states, _ = loc.take_trajectory()
    t, states = last_per_stamp(t, states)
    np.testing.assert_array_equal(t, replayed.t_ns)
    np.testing.assert_array_equal(states[:, 0], replayed.x)
    assert loc.counts()["too_late"] == 0


def test_scans_later_than_the_lag_are_dropped_and_counted(inputs):
    loc = new_localizer(max_lag=0.1)
    kept = feed(loc, with_late_scans(inputs, 300_000_000))
    n_scans = sum(kind == "scan" for _, kind, _ in inputs)
    dropped = kept.count(False)
    assert dropped == n_scans - 1, "every scan but the last (flushed) comes too late"
    assert loc.counts()["too_late"] == dropped


def test_the_pose_now_runs_ahead_of_the_fused_state(inputs):
    loc = new_localizer()
    for t, kind, payload in inputs[:200]:
        if kind == "wheels":
            loc.add_wheel_angles(t, *payload)
    assert loc.held > 0
    t_now, state_now, cov_now = loc.pose_now()
    assert t_now == max(t for t, kind, _ in inputs[:200] if kind == "wheels")
    assert t_now > loc.t_ns
    assert state_now.shape == (3,) and cov_now.shape == (3, 3)
    assert np.trace(cov_now) > np.trace(loc.covariance), "predicted further"
    loc.flush()
    np.testing.assert_array_equal(loc.state, state_now)
    np.testing.assert_array_equal(loc.covariance, cov_now)


def test_bad_arguments_are_refused_with_their_name():
    with pytest.raises(ValueError, match="mode"):
        ekf_loc.TimedLocalizer([0, 0, 0], P0, mode="sonar")
    with pytest.raises(ValueError, match="max_lag"):
        ekf_loc.TimedLocalizer([0, 0, 0], P0, max_lag=-1.0)
    loc = ekf_loc.TimedLocalizer([0, 0, 0], P0)
    with pytest.raises(ValueError, match="heading"):
        loc.add_heading(1, float("nan"))
    with pytest.raises(ValueError, match="xy"):
        loc.add_position(1, [1.0, 2.0, 3.0], np.eye(2))
    with pytest.raises(ValueError, match="global localization"):
        ekf_loc.TimedLocalizer([0, 0, 0], P0, global_localization=True)
