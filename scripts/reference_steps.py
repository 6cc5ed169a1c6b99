"""Where a log's reference trajectory disagrees with both its odometry and its laser.

A CARMEN "corrected" log's reference is itself an estimate (the poses a scan-matching
SLAM gave each scan). Where one of its steps between consecutive scans disagrees with
the odometry's by more than `--min-disagreement` (0.3 m), the two scans are aligned to
each other (point-to-point ICP, started from the odometry's step and from the
reference's, the start that matches more points kept). The step is then

- `laser=odom`: the scans agree with the odometry (within 0.15 m) and not with the
  reference (more than 0.3 m off) — the reference stepped where the robot did not;
- `laser=ref`: the other way round — the odometry slipped;
- `unclear`: fewer than half the points matched, or neither fits.

With an estimate (TUM, as `ekf replay --tum` or `ekf corpus` write it), it also scores
it as `ekf corpus` does (the last estimate at or before each reference pose) over all
reference poses and without the ones from each `laser=odom` step until the error is
back under 0.2 m.

Usage (the packages of tests/python/requirements.txt):

    python scripts/reference_steps.py LOG.mcap [--estimate EST.tum]
"""

import argparse
import bisect
import math
from dataclasses import dataclass

import numpy as np
from mcap_ros2.reader import read_ros2_messages
from scipy.spatial import cKDTree

# ICP: correspondences within a radius that shrinks from 1.5 m to 0.2 m, inliers at 0.15 m.
ICP_ITERATIONS = 60
INLIER_M = 0.15
AGREE_M = 0.15
DISAGREE_M = 0.3
MIN_INLIER_SHARE = 0.5


@dataclass
class Step:
    t0: float
    t1: float
    odom_vs_ref_m: float
    kind: str
    inliers: float


def stamp(header) -> float:
    return header.stamp.sec + header.stamp.nanosec * 1e-9


def yaw(q) -> float:
    return math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z))


def relative(a, b) -> np.ndarray:
    """Pose b in the frame of pose a: (dx, dy, dθ)."""
    dx, dy = b[0] - a[0], b[1] - a[1]
    c, s = math.cos(a[2]), math.sin(a[2])
    dth = (b[2] - a[2] + math.pi) % (2 * math.pi) - math.pi
    return np.array([c * dx + s * dy, -s * dx + c * dy, dth])


def transform(points: np.ndarray, x: np.ndarray) -> np.ndarray:
    c, s = math.cos(x[2]), math.sin(x[2])
    return points @ np.array([[c, s], [-s, c]]) + x[:2]


def icp(a: np.ndarray, b: np.ndarray, x0: np.ndarray) -> tuple[np.ndarray, float]:
    """The pose `x` of scan `b` in the frame of scan `a` that puts b's points on a's,
    from `x0`; and the share of b's points within INLIER_M of a's there."""
    tree = cKDTree(a)
    x = np.array(x0, dtype=float)
    for k in range(ICP_ITERATIONS):
        p = transform(b, x)
        d, i = tree.query(p)
        m = d < max(1.5 * (1 - k / 30), 0.2)
        if m.sum() < 3:
            break
        p, q = p[m], a[i[m]]
        pc, qc = p.mean(0), q.mean(0)
        u, _, vt = np.linalg.svd((p - pc).T @ (q - qc))
        r = vt.T @ u.T
        if np.linalg.det(r) < 0:
            vt[1] *= -1
            r = vt.T @ u.T
        c, s = math.cos(x[2]), math.sin(x[2])
        rn = r @ np.array([[c, -s], [s, c]])
        tn = r @ x[:2] + qc - r @ pc
        x = np.array([tn[0], tn[1], math.atan2(rn[1, 0], rn[0, 0])])
    d, _ = tree.query(transform(b, x))
    return x, float((d < INLIER_M).mean())


def classify(odom: np.ndarray, ref: np.ndarray, laser: np.ndarray, inliers: float) -> str:
    to_odom = math.hypot(*(laser[:2] - odom[:2]))
    to_ref = math.hypot(*(laser[:2] - ref[:2]))
    if inliers < MIN_INLIER_SHARE:
        return "unclear"
    if to_odom < AGREE_M and to_ref > DISAGREE_M:
        return "laser=odom"
    if to_ref < AGREE_M and to_odom > DISAGREE_M:
        return "laser=ref"
    return "unclear"


def read_log(path):
    scans, odom, ref = [], [], []
    for m in read_ros2_messages(path, topics=["/scan", "/odom", "/ground_truth"]):
        msg, topic = m.ros_msg, m.channel.topic
        if topic == "/scan":
            r = np.asarray(msg.ranges, dtype=float)
            a = msg.angle_min + msg.angle_increment * np.arange(len(r))
            ok = np.isfinite(r) & (r > msg.range_min) & (r < msg.range_max)
            scans.append((stamp(msg.header), np.c_[r[ok] * np.cos(a[ok]), r[ok] * np.sin(a[ok])]))
        else:
            p = msg.pose.pose
            pose = (p.position.x, p.position.y, yaw(p.orientation))
            (odom if topic == "/odom" else ref).append((stamp(msg.header), pose))
    return scans, odom, ref


def pose_at(series, times, t):
    """The last pose of `series` at or before `t`."""
    return series[max(bisect.bisect_right(times, t + 1e-9) - 1, 0)][1]


def steps(scans, odom, ref, min_disagreement: float) -> list[Step]:
    ot, rt = [s[0] for s in odom], [s[0] for s in ref]
    out = []
    for (t0, a), (t1, b) in zip(scans, scans[1:]):
        do = relative(pose_at(odom, ot, t0), pose_at(odom, ot, t1))
        dr = relative(pose_at(ref, rt, t0), pose_at(ref, rt, t1))
        gap = math.hypot(*(do[:2] - dr[:2]))
        if gap <= min_disagreement or len(a) < 3 or len(b) < 3:
            continue
        (xo, fo), (xr, fr) = icp(a, b, do), icp(a, b, dr)
        laser, inliers = (xo, fo) if fo >= fr else (xr, fr)
        out.append(Step(t0, t1, gap, classify(do, dr, laser, inliers), inliers))
    return out


def score(ref, estimate_path: str, contradicted: list[float]):
    est = []
    with open(estimate_path) as f:
        for line in f:
            if line.strip() and not line.startswith("#"):
                v = [float(x) for x in line.split()]
                est.append((v[0], v[1], v[2]))
    et = [e[0] for e in est]
    errors = []
    for t, p in ref:
        i = bisect.bisect_right(et, t + 1e-9) - 1
        if i >= 0:
            errors.append((t, math.hypot(est[i][1] - p[0], est[i][2] - p[1])))
    left_out = set()
    for t1 in contradicted:
        for i, (t, e) in enumerate(errors):
            if t < t1 - 1e-9:
                continue
            if e < 0.2:
                break
            left_out.add(i)
    sse = sum(e * e for _, e in errors)
    sse_out = sum(errors[i][1] ** 2 for i in left_out)
    n, k = len(errors), len(left_out)
    return n, math.sqrt(sse / n), k, math.sqrt((sse - sse_out) / (n - k))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("log")
    ap.add_argument("--estimate")
    ap.add_argument("--min-disagreement", type=float, default=0.3)
    args = ap.parse_args()
    scans, odom, ref = read_log(args.log)
    found = steps(scans, odom, ref, args.min_disagreement)
    for s in found:
        print(f"{s.t0:10.1f} → {s.t1:10.1f}  odometry vs reference {s.odom_vs_ref_m:.2f} m  "
              f"{s.kind:10s}  inliers {s.inliers:.2f}")
    kinds = {k: sum(s.kind == k for s in found) for k in ("laser=odom", "laser=ref", "unclear")}
    print(f"{len(scans) - 1} scan steps, {len(found)} where odometry and reference disagree "
          f"by more than {args.min_disagreement} m: {kinds}")
    if args.estimate:
        n, rmse, k, rmse_rest = score(ref, args.estimate,
                                      [s.t1 for s in found if s.kind == "laser=odom"])
        print(f"estimate: RMSE {rmse:.3f} m over {n} reference poses; {rmse_rest:.3f} m "
              f"without the {k} after a laser=odom step (until the error is under 0.2 m)")


if __name__ == "__main__":
    main()
