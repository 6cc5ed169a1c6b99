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
