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

The laser's step is turned into the robot's with the laser's mount from `/tf_static`
(`base_link` to the scan's frame; none: the laser at the robot's origin). A step is only
judged when both starts converge to the same alignment (within 0.15 m) or one matches
clearly more points (a tenth of the scan): where the points constrain little, each start
stays near where it began, and the better of two near-equal fits says nothing.

With an estimate (TUM, as `ekf replay --tum` or `ekf corpus` write it), it also gives the
position RMSE as `ekf replay` computes it (as `evo_ape` without alignment: each pose of
the trajectory with fewer poses paired with the nearest of the other within 10 ms), over
all pairs and without those from each `laser=odom` step until the error is back under
0.2 m.

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
# A start's alignment wins over the other's by at least this share of the scan's points.
CLEAR_MARGIN = 0.1
# Pairs of poses further apart in time are not compared (evo's max_diff, ekf replay's).
MAX_DIFF_NS = 10_000_000


@dataclass
class Step:
    t0_ns: int
    t1_ns: int
    odom_vs_ref_m: float
    kind: str
    inliers: float


def stamp(header) -> int:
    """The header's stamp in integer nanoseconds."""
    return header.stamp.sec * 1_000_000_000 + header.stamp.nanosec


def yaw(q) -> float:
    return math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z))


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
    """The scans (stamp, points in the laser frame, frame id), odometry and reference
    poses (stamp, (x, y, θ)) and the laser mounts by frame id from `/tf_static`."""
    scans, odom, ref, mounts = [], [], [], {}
    topics = ["/scan", "/odom", "/ground_truth", "/tf_static"]
    for m in read_ros2_messages(path, topics=topics):
        msg, topic = m.ros_msg, m.channel.topic
        if topic == "/scan":
            r = np.asarray(msg.ranges, dtype=float)
            a = msg.angle_min + msg.angle_increment * np.arange(len(r))
            ok = np.isfinite(r) & (r > msg.range_min) & (r < msg.range_max)
            points = np.c_[r[ok] * np.cos(a[ok]), r[ok] * np.sin(a[ok])]
            scans.append((stamp(msg.header), points, msg.header.frame_id))
        elif topic == "/tf_static":
            for tf in msg.transforms:
                t = tf.transform.translation
                mounts[tf.child_frame_id] = (t.x, t.y, yaw(tf.transform.rotation))
        else:
            p = msg.pose.pose
            pose = (p.position.x, p.position.y, yaw(p.orientation))
            (odom if topic == "/odom" else ref).append((stamp(msg.header), pose))
    return scans, odom, ref, mounts


def compose(a, b) -> np.ndarray:
    """a ⊕ b."""
    c, s = math.cos(a[2]), math.sin(a[2])
    th = (a[2] + b[2] + math.pi) % (2 * math.pi) - math.pi
    return np.array([a[0] + c * b[0] - s * b[1], a[1] + s * b[0] + c * b[1], th])


def inverse(a) -> np.ndarray:
    c, s = math.cos(a[2]), math.sin(a[2])
    return np.array([-c * a[0] - s * a[1], s * a[0] - c * a[1], -a[2]])


def relative(a, b) -> np.ndarray:
    """Pose b in the frame of pose a: a⁻¹ ⊕ b."""
    return compose(inverse(a), b)


def robot_step(sensor_step, mount) -> np.ndarray:
    """The robot's step for the laser's step `sensor_step`, the laser at `mount`."""
    return compose(compose(mount, sensor_step), inverse(mount))


def pose_at(series, times, t):
    """The last pose of `series` at or before `t` (ns)."""
    return series[max(bisect.bisect_right(times, t) - 1, 0)][1]


def judge(a, b, odom, ref, mount) -> tuple[str, float]:
    """Aligns scan `b` to scan `a` from the odometry's and the reference's robot steps;
    the classification and the matched share of the alignment that decided."""
    to_sensor = lambda step: robot_step(step, inverse(mount))  # noqa: E731
    (xo, fo), (xr, fr) = icp(a, b, to_sensor(odom)), icp(a, b, to_sensor(ref))
    xo, xr = robot_step(xo, mount), robot_step(xr, mount)
    if math.hypot(*(xo[:2] - xr[:2])) < AGREE_M:
        laser, inliers = (xo, fo) if fo >= fr else (xr, fr)
    elif abs(fo - fr) >= CLEAR_MARGIN:
        laser, inliers = (xo, fo) if fo > fr else (xr, fr)
    else:
        return "unclear", max(fo, fr)
    return classify(odom, ref, laser, inliers), inliers


def steps(scans, odom, ref, mounts, min_disagreement: float) -> list[Step]:
    ot, rt = [s[0] for s in odom], [s[0] for s in ref]
    out = []
    for (t0, a, frame), (t1, b, _) in zip(scans, scans[1:]):
        do = relative(pose_at(odom, ot, t0), pose_at(odom, ot, t1))
        dr = relative(pose_at(ref, rt, t0), pose_at(ref, rt, t1))
        gap = math.hypot(*(do[:2] - dr[:2]))
        if gap <= min_disagreement or len(a) < 3 or len(b) < 3:
            continue
        kind, inliers = judge(a, b, do, dr, np.array(mounts.get(frame, (0.0, 0.0, 0.0))))
        out.append(Step(t0, t1, gap, kind, inliers))
    return out


def read_tum(path):
    """A TUM trajectory: (stamp ns, (x, y))."""
    out = []
    with open(path) as f:
        for line in f:
            if line.strip() and not line.startswith("#"):
                v = line.split()
                out.append((round(float(v[0]) * 1e9), (float(v[1]), float(v[2]))))
    return out


def pair_errors(estimate, reference):
    """Position errors (reference stamp ns, m) as `ekf replay` pairs poses: each pose of
    the trajectory with fewer poses with the nearest of the other within MAX_DIFF_NS
    (ties: the earlier)."""
    est_queries = len(estimate) < len(reference)
    queries, candidates = (estimate, reference) if est_queries else (reference, estimate)
    times = [c[0] for c in candidates]
    out = []
    for t, q in queries:
        i = bisect.bisect_left(times, t)
        near = [j for j in (i - 1, i) if 0 <= j < len(times)]
        if not near:
            continue
        j = min(near, key=lambda j: (abs(times[j] - t), j))
        if abs(times[j] - t) > MAX_DIFF_NS:
            continue
        c = candidates[j][1]
        out.append((times[j] if est_queries else t, math.hypot(q[0] - c[0], q[1] - c[1])))
    return sorted(out)


def score(errors, contradicted_ns):
    """RMSE over all `errors` (stamp ns, m), and without those from each stamp of
    `contradicted_ns` until the error is back under 0.2 m: (n, rmse, left out, rmse)."""
    left_out = set()
    for t1 in contradicted_ns:
        for i, (t, e) in enumerate(errors):
            if t < t1:
                continue
            if e < 0.2:
                break
            left_out.add(i)
    kept = [e for i, (_, e) in enumerate(errors) if i not in left_out]
    return len(errors), rmse([e for _, e in errors]), len(left_out), rmse(kept)


def rmse(errors) -> float:
    """The root mean square of `errors` (nan when there are none)."""
    return math.sqrt(sum(e * e for e in errors) / len(errors)) if errors else math.nan


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("log")
    ap.add_argument("--estimate")
    ap.add_argument("--min-disagreement", type=float, default=0.3)
    args = ap.parse_args()
    scans, odom, ref, mounts = read_log(args.log)
    found = steps(scans, odom, ref, mounts, args.min_disagreement)
    for s in found:
        print(f"{s.t0_ns * 1e-9:10.1f} → {s.t1_ns * 1e-9:10.1f}  odometry vs reference {s.odom_vs_ref_m:.2f} m  "
              f"{s.kind:10s}  inliers {s.inliers:.2f}")
    kinds = {k: sum(s.kind == k for s in found) for k in ("laser=odom", "laser=ref", "unclear")}
    print(f"{len(scans) - 1} scan steps, {len(found)} where odometry and reference disagree "
          f"by more than {args.min_disagreement} m: {kinds}")
    if args.estimate:
        errors = pair_errors(read_tum(args.estimate), ref)
        contradicted = [s.t1_ns for s in found if s.kind == "laser=odom"]
        n, rmse, k, rmse_rest = score(errors, contradicted)
        print(f"estimate: RMSE {rmse:.3f} m over {n} pairs; {rmse_rest:.3f} m without the "
              f"{k} after a laser=odom step (until the error is under 0.2 m)")


if __name__ == "__main__":
    main()
