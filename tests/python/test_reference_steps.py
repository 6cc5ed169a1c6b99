"""scripts/reference_steps.py: its scan alignment recovers a known motion, and a step is
classified by which of odometry and reference the laser agrees with."""

import math
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "scripts"))
import reference_steps as rs  # noqa: E402


def room_scan(pose):
    """Points of a 6 m × 4 m room's walls and a 0.5 m box, seen from `pose` (x, y, θ)."""
    walls = [((0, 0), (6, 0)), ((6, 0), (6, 4)), ((6, 4), (0, 4)), ((0, 4), (0, 0)),
             ((4, 1), (4.5, 1)), ((4.5, 1), (4.5, 1.5))]
    pts = []
    for (x0, y0), (x1, y1) in walls:
        n = int(math.hypot(x1 - x0, y1 - y0) / 0.05)
        for k in range(n + 1):
            pts.append((x0 + (x1 - x0) * k / n, y0 + (y1 - y0) * k / n))
    world = np.array(pts)
    c, s = math.cos(pose[2]), math.sin(pose[2])
    d = world - np.array(pose[:2])
    return np.c_[c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1]]


def test_icp_recovers_the_motion_between_two_scans():
    a_pose, b_pose = (2.0, 1.5, 0.2), (2.4, 1.3, 0.3)
    a, b = room_scan(a_pose), room_scan(b_pose)
    truth = rs.relative(a_pose, b_pose)
    start = truth + np.array([0.2, -0.15, 0.05])
    x, inliers = rs.icp(a, b, start)
    # Within a third of the 0.15 m the classification allows (point-to-point ICP on
    # evenly spaced points stops about 2 cm short).
    assert math.hypot(*(x[:2] - truth[:2])) < 0.05
    assert abs(x[2] - truth[2]) < math.radians(1.0)
    assert inliers > 0.95


def test_relative_pose_is_in_the_first_poses_frame():
    r = rs.relative((1.0, 1.0, math.pi / 2), (1.0, 3.0, math.pi))
    assert np.allclose(r, [2.0, 0.0, math.pi / 2])


def test_a_step_is_judged_by_the_laser():
    odom, ref = np.array([1.0, 0.0, 0.0]), np.array([1.0, 0.8, 0.0])
    assert rs.classify(odom, ref, np.array([1.05, 0.02, 0.0]), 0.9) == "laser=odom"
    assert rs.classify(odom, ref, np.array([1.0, 0.75, 0.0]), 0.9) == "laser=ref"
    assert rs.classify(odom, ref, np.array([1.0, 0.4, 0.0]), 0.9) == "unclear"
    assert rs.classify(odom, ref, np.array([1.05, 0.02, 0.0]), 0.3) == "unclear"


def test_a_laser_step_becomes_the_robots_through_the_mount():
    mount = np.array([0.3, 0.1, 0.2])
    robot = np.array([0.5, -0.2, 0.4])
    # The laser's step is mount⁻¹ ⊕ robot ⊕ mount; robot_step undoes it.
    sensor = rs.compose(rs.compose(rs.inverse(mount), robot), mount)
    assert np.allclose(rs.robot_step(sensor, mount), robot)
    assert np.allclose(rs.robot_step(robot, np.zeros(3)), robot)


def test_starts_that_end_apart_with_equal_fits_are_unclear():
    # A corridor: two long parallel walls and nothing across. Started 0.5 m apart
    # along it, each alignment stays where it began and matches every point.
    x = np.arange(-10.0, 10.0, 0.05)
    a = np.r_[np.c_[x, np.full_like(x, 1.0)], np.c_[x, np.full_like(x, -1.0)]]
    b = a[(a[:, 0] > -5) & (a[:, 0] < 5)]
    odom, ref = np.array([0.0, 0.0, 0.0]), np.array([0.5, 0.0, 0.0])
    kind, _ = rs.judge(a, b, odom, ref, np.zeros(3))
    assert kind == "unclear"


def test_pairs_are_made_as_ekf_replay_makes_them_and_contradicted_stretches_left_out():
    ms = 1_000_000
    reference = [(k * 100 * ms, (float(k), 0.0)) for k in range(6)]
    # One estimate per reference pose, 2 ms late; the one for k = 4 is 30 ms late (no
    # pair); k = 2 and 3 are 1 m and 0.5 m off, the rest 0.1 m.
    off = {2: 1.0, 3: 0.5}
    estimate = [(k * 100 * ms + (30 if k == 4 else 2) * ms, (k + off.get(k, 0.1), 0.0))
                for k in range(6)]
    errors = rs.pair_errors(estimate, reference)
    assert [t for t, _ in errors] == [0, 100 * ms, 200 * ms, 300 * ms, 500 * ms]
    assert np.allclose([e for _, e in errors], [0.1, 0.1, 1.0, 0.5, 0.1])
    n, rmse, left_out, rmse_rest = rs.score(errors, [200 * ms])
    assert (n, left_out) == (5, 2)
    assert math.isclose(rmse, math.sqrt((0.01 * 3 + 1.0 + 0.25) / 5))
    assert math.isclose(rmse_rest, 0.1)
