//! Walls the line extraction missed. Split-and-merge cuts a wall at clutter in front of it,
//! at gaps, and where it is seen so obliquely that its points are far apart; the pieces
//! are then too short to be lines of their own, though together they locate the robot
//! as well as one line. So once a scan's matched lines are fused (at least
//! [`super::REFIT_AFTER_LINES`] of them, so that the pose they give is confirmed), every
//! beam with a valid reading that is not on one of those lines is traced from the updated
//! sensor pose to the first wall of the map it meets, and kept if its reading lies on that
//! wall. The kept beams are grouped by wall, in pieces of at least [`MIN_RUN`]
//! consecutive beams (a lone beam near a wall is as likely clutter). A wall that no
//! fused line lies on and whose pieces have enough points is fitted as an extracted line
//! is ([`crate::LineExtractor::fit_beams`]: the same weighted fit, refused where a point
//! lies off the line by more than the split distance) and fused as a matched line, with
//! the same noise and gate.
//!
//! A beam with the unit direction `u` (world frame) from the sensor at `s` meets the wall
//! from `a` to `b` (`e = b − a`) at `t = (a − s) × e / (u × e)`, inside it when
//! `k = (a − s) × u / (u × e)` lies in `[0, 1]`; the first wall it meets is the one of
//! smallest `t > 0`. Only walls within the longest reading of the beams left (fewer than
//! [`MIN_RUN`] beams left: none), and only
//! the beams whose bearings lie between those of a wall's end points (and the one beside
//! each), are tried. The reading `r` gives the point `p = s + r u` at the normal distance
//! `d = (n·u)(r − t)` from the wall, `n` its unit normal, with the Jacobian
//! `h = ∂d/∂(x, y, θ) = (n_x, n_y, −n_x (p_y − y) + n_y (p_x − x))`. The point lies on the
//! wall when `d² ≤ χ²₁(p) · (σ_r² (n·u)² + σ_map,r² + h P hᵀ)`, `σ_r` the extraction's
//! range noise, `σ_map,r` the matching's map noise and `p` the matching's gate
//! probability.

use crate::{LaserScan, LineMap, ObservedLine};
use alloc::vec::Vec;
use core::ops::Range;
use ekf_core::Pose2;
use nalgebra::Matrix3;

/// Fewest consecutive beams on one wall that count as a piece of it.
const MIN_RUN: usize = 3;

/// What the beams are traced with: the filter's state after the lines were fused.
pub(super) struct Tracing<'a> {
    /// The robot's pose.
    pub pose: Pose2<f64>,
    /// Its covariance.
    pub covariance: &'a Matrix3<f64>,
    /// The laser's pose on the robot.
    pub mount: Pose2<f64>,
    /// `σ_r²` (m²).
    pub range_var: f64,
    /// `σ_map,r²` (m²).
    pub map_var: f64,
    /// `χ²₁(p)`.
    pub gate: f64,
}

/// The scratch buffers of the search, kept across scans so it does not allocate once warm.
#[derive(Debug, Clone, Default)]
pub(super) struct MissedWalls {
    /// Per beam: `t` of the first wall along it and that wall, if any.
    hits: Vec<Option<(f64, usize)>>,
    /// Per beam: without a valid reading, or on a line fused in this scan.
    skip: Vec<bool>,
    /// Runs of consecutive beams on one wall, sorted by wall.
    pieces: Vec<(usize, Range<usize>)>,
    /// The runs of [`pieces`](Self::pieces) alone, and per wall the range of them.
    runs: Vec<Range<usize>>,
    groups: Vec<(usize, Range<usize>)>,
}

impl MissedWalls {
    /// Finds the walls of `map` that the beams of `scan` (directions `dirs` in the sensor
    /// frame) lie on at the state `at`, leaving out the beams between the end points of
    /// the lines `fused` (sensor frame) and the walls for which `taken` is true.
    pub(super) fn find(
        &mut self,
        scan: &LaserScan<'_>,
        dirs: (&[f64], &[f64]),
        map: &LineMap,
        at: &Tracing<'_>,
        fused: &[ObservedLine],
        taken: impl Fn(usize) -> bool,
    ) {
        let n = scan.ranges.len().min(dirs.0.len()).min(dirs.1.len());
        self.hits.clear();
        self.hits.resize(n, None);
        self.mark_skipped(scan, n, fused);
        self.pieces.clear();
        self.runs.clear();
        self.groups.clear();
        // The beams left to trace, and the longest of their readings.
        let (left, far) = scan
            .ranges
            .iter()
            .zip(&self.skip)
            .filter(|(_, &skip)| !skip)
            .fold((0_usize, 0.0_f64), |(k, m), (&r, _)| {
                (k + 1, m.max(f64::from(r)))
            });
        if left < MIN_RUN {
            return;
        }
        let sensor = at.pose.compose(&at.mount);
        let (st, ct) = libm::sincos(sensor.theta);
        for (w, wall) in map.segments.iter().enumerate() {
            // The sensor farther than `far` from the wall's bounding box: out of reach.
            let (a, b) = (&wall.start, &wall.end);
            if sensor.x < a.x.min(b.x) - far
                || sensor.x > a.x.max(b.x) + far
                || sensor.y < a.y.min(b.y) - far
                || sensor.y > a.y.max(b.y) + far
            {
                continue;
            }
            let (ax, ay) = (a.x - sensor.x, a.y - sensor.y);
            let (ex, ey) = (b.x - a.x, b.y - a.y);
            // ... or from the wall itself: the nearest point a + k e, k = −(a − s)·e / |e|²
            // clamped to [0, 1].
            let k = (-(ax * ex + ay * ey) / (ex * ex + ey * ey)).clamp(0.0, 1.0);
            let (nearest_x, nearest_y) = (ax + k * ex, ay + k * ey);
            if nearest_x * nearest_x + nearest_y * nearest_y > far * far {
                continue;
            }
            // The ray s + t u meets the wall a + k e (0 ≤ k ≤ 1) where
            // t = (a − s) × e / (u × e) and k = (a − s) × u / (u × e).
            let a_cross_e = ax * ey - ay * ex;
            for i in beams_between(scan, n, &sensor, a, b) {
                if self.skip.get(i) != Some(&false) {
                    continue;
                }
                let (Some(&c), Some(&s)) = (dirs.0.get(i), dirs.1.get(i)) else {
                    continue;
                };
                let (ux, uy) = (ct * c - st * s, st * c + ct * s);
                let u_cross_e = ux * ey - uy * ex;
                if libm::fabs(u_cross_e) < 1e-12 {
                    continue;
                }
                let t = a_cross_e / u_cross_e;
                let k = (ax * uy - ay * ux) / u_cross_e;
                if let Some(hit) = self.hits.get_mut(i) {
                    if t > 0.0 && (0.0..=1.0).contains(&k) && hit.is_none_or(|(best, _)| t < best) {
                        *hit = Some((t, w));
                    }
                }
            }
        }
        self.group(scan, dirs, map, at, &sensor, taken);
    }

    /// Marks the beams without a valid reading and those whose bearings lie between the
    /// end points of a line of `fused`.
    fn mark_skipped(&mut self, scan: &LaserScan<'_>, n: usize, fused: &[ObservedLine]) {
        self.skip.clear();
        self.skip
            .extend(scan.ranges.iter().take(n).map(|&r| !scan.is_valid(r)));
        let here = Pose2::identity();
        for line in fused {
            for i in beams_between(scan, n, &here, &line.start, &line.end) {
                if let Some(skip) = self.skip.get_mut(i) {
                    *skip = true;
                }
            }
        }
    }

    /// Keeps the beams whose reading lies on the wall they meet (see the module), in runs
    /// of consecutive beams per wall, grouped by wall.
    fn group(
        &mut self,
        scan: &LaserScan<'_>,
        dirs: (&[f64], &[f64]),
        map: &LineMap,
        at: &Tracing<'_>,
        sensor: &Pose2<f64>,
        taken: impl Fn(usize) -> bool,
    ) {
        self.pieces.clear();
        let (st, ct) = libm::sincos(sensor.theta);
        let p = at.covariance;
        for (i, hit) in self.hits.iter().enumerate() {
            let Some((t, w)) = *hit else { continue };
            let (Some(&range), Some(wall)) = (scan.ranges.get(i), map.segments.get(w)) else {
                continue;
            };
            if taken(w) {
                continue;
            }
            let (Some(&c), Some(&s)) = (dirs.0.get(i), dirs.1.get(i)) else {
                continue;
            };
            let r = f64::from(range);
            let (ux, uy) = (ct * c - st * s, st * c + ct * s);
            // A unit normal of the wall, from its end points (its sign does not matter).
            let (ex, ey) = (wall.end.x - wall.start.x, wall.end.y - wall.start.y);
            let length = libm::hypot(ex, ey);
            let (nx, ny) = (ey / length, -ex / length);
            let facing = nx * ux + ny * uy;
            let d = facing * (r - t);
            let (px, py) = (sensor.x + r * ux, sensor.y + r * uy);
            let h = nalgebra::Vector3::new(nx, ny, -nx * (py - at.pose.y) + ny * (px - at.pose.x));
            let var = at.range_var * facing * facing + at.map_var + (h.transpose() * p * h).x;
            if d * d > at.gate * var {
                continue;
            }
            match self.pieces.last_mut() {
                Some((last, run)) if *last == w && run.end == i => run.end = i + 1,
                _ => self.pieces.push((w, i..i + 1)),
            }
        }
        let n = self.hits.len();
        // A wall across the seam of a scan that goes all round: its piece at the end and
        // its piece at the start are one, and its pieces are in scan order from the
        // seam's far side (a wall subtends less than half a turn, so its beams in the
        // last half of the scan come before those in the first).
        let seam_wall = match (self.pieces.first(), self.pieces.last()) {
            (Some((w0, head)), Some((w1, tail)))
                if self.pieces.len() > 1
                    && w0 == w1
                    && head.start == 0
                    && tail.end == n
                    && full_turn(scan, n) =>
            {
                Some((*w0, head.len() + tail.len()))
            }
            _ => None,
        };
        self.pieces.retain(|(w, run)| {
            run.len() >= MIN_RUN
                || seam_wall.is_some_and(|(seam, joined)| {
                    *w == seam && joined >= MIN_RUN && (run.start == 0 || run.end == n)
                })
        });
        let in_scan_order = |w: usize, run: &Range<usize>| -> isize {
            let start = run.start as isize;
            match seam_wall {
                Some((seam, _)) if seam == w && 2 * run.start >= n => start - n as isize,
                _ => start,
            }
        };
        self.pieces
            .sort_unstable_by_key(|(w, run)| (*w, in_scan_order(*w, run)));
        self.runs.clear();
        self.groups.clear();
        for (w, run) in &self.pieces {
            match self.groups.last_mut() {
                Some((last, runs)) if last == w => runs.end += 1,
                _ => self.groups.push((*w, self.runs.len()..self.runs.len() + 1)),
            }
            self.runs.push(run.clone());
        }
    }

    /// Walls found by [`find`](Self::find).
    pub(super) fn len(&self) -> usize {
        self.groups.len()
    }

    /// The `k`-th wall found and its runs of beams, in scan order.
    pub(super) fn get(&self, k: usize) -> Option<(usize, &[Range<usize>])> {
        let (w, runs) = self.groups.get(k)?;
        Some((*w, self.runs.get(runs.clone())?))
    }
}

/// The beams of `scan` (the first `n`) whose bearings, from `sensor`, lie between those of
/// the points `a` and `b` (the shorter way round), and the beam next to each end.
fn beams_between(
    scan: &LaserScan<'_>,
    n: usize,
    sensor: &Pose2<f64>,
    a: &nalgebra::Point2<f64>,
    b: &nalgebra::Point2<f64>,
) -> impl Iterator<Item = usize> {
    let tau = core::f64::consts::TAU;
    let bearing =
        |p: &nalgebra::Point2<f64>| atan2_approx(p.y - sensor.y, p.x - sensor.x) - sensor.theta;
    let (fa, fb) = (bearing(a), bearing(b));
    let step = libm::fabs(scan.angle_increment);
    let sign = scan.angle_increment.signum();
    // Bearings measured from the first beam, in the beams' sense, in [0, 2π).
    let from_first = |phi: f64| reduce(sign * (phi - scan.angle_min), 0.0);
    let turn = sign * reduce(fb - fa, -core::f64::consts::PI);
    let (lo, span) = if turn >= 0.0 {
        (from_first(fa), turn)
    } else {
        (from_first(fb), -turn)
    };
    let last = n.saturating_sub(1);
    // The interval [lo, lo + span], and its part past 2π wrapped to the start, widened
    // by a beam at each end for the error of `atan2_approx`: from the beam before the
    // first at or after `from` to the one after the last at or before `to`. Both ends are
    // ≥ 0, so the conversions round down (and saturate on a non-finite value).
    let index = move |from: f64, to: f64| {
        let below = (from / step) as usize;
        let first = if (below as f64) * step < from {
            below
        } else {
            below.saturating_sub(1)
        };
        let end = if to < 0.0 {
            0
        } else {
            ((to / step) as usize).saturating_add(1).min(last)
        };
        (first <= end && n > 0).then_some(first..end + 1)
    };
    let main = index(lo, lo + span);
    // Past the last beam, and, on a scan that goes all round, the padding beam past
    // either end too, continue at the other end.
    let full = full_turn(scan, n);
    let wrapped = (lo + span > tau || (full && lo + span + step > tau))
        .then(|| index(0.0, lo + span - tau))
        .flatten();
    let before_first = (full && lo <= 0.0 && n > 0).then_some(last);
    main.into_iter()
        .flatten()
        .chain(wrapped.into_iter().flatten())
        .chain(before_first)
}

/// Whether the first `n` beams of `scan` go once all round, the last beside the first
/// (to within half a beam).
fn full_turn(scan: &LaserScan<'_>, n: usize) -> bool {
    let step = libm::fabs(scan.angle_increment);
    libm::fabs(n as f64 * step - core::f64::consts::TAU) <= 0.5 * step
}

/// `angle` moved by whole turns into `[lo, lo + 2π)`: by a loop of additions for an angle
/// within a few turns of it (the bearings here; cheaper than a division), by the IEEE
/// remainder for one farther off (a scan's `angle_min` may be any finite number).
fn reduce(mut angle: f64, lo: f64) -> f64 {
    let tau = core::f64::consts::TAU;
    if !angle.is_finite() {
        return lo;
    }
    if libm::fabs(angle - lo) > 4.0 * tau {
        // In [lo, lo + 2π] up to rounding, which the loops below settle.
        angle =
            lo + core::f64::consts::PI + libm::remainder(angle - lo - core::f64::consts::PI, tau);
    }
    while angle < lo {
        angle += tau;
    }
    while angle >= lo + tau {
        angle -= tau;
    }
    angle
}

/// `atan2(y, x)` within 2·10⁻⁵ rad, several times cheaper than `libm::atan2`: the
/// polynomial `atan(z) ≈ z (0.99997726 − 0.33262347 z² + 0.19354346 z⁴ − 0.11643287 z⁶ +
/// 0.05265332 z⁸ − 0.01172120 z¹⁰)` on `z = min(|x|, |y|) / max(|x|, |y|) ∈ [0, 1]`, moved
/// to the octant of `(x, y)`. 0 for the origin.
fn atan2_approx(y: f64, x: f64) -> f64 {
    let (ax, ay) = (libm::fabs(x), libm::fabs(y));
    let (small, big) = if ax < ay { (ax, ay) } else { (ay, ax) };
    if big == 0.0 {
        return 0.0;
    }
    let z = small / big;
    let z2 = z * z;
    let mut a = z
        * (0.999_977_26
            + z2 * (-0.332_623_47
                + z2 * (0.193_543_46
                    + z2 * (-0.116_432_87 + z2 * (0.052_653_32 - 0.011_721_20 * z2)))));
    if ay > ax {
        a = core::f64::consts::FRAC_PI_2 - a;
    }
    if x < 0.0 {
        a = core::f64::consts::PI - a;
    }
    if y < 0.0 {
        -a
    } else {
        a
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use alloc::vec::Vec;
    use ekf_core::wrap_angle;
    use nalgebra::Point2;

    fn header(angle_min: f64, angle_increment: f64, ranges: &[f32]) -> LaserScan<'_> {
        LaserScan {
            angle_min,
            angle_increment,
            range_min: 0.0,
            range_max: 10.0,
            ranges,
        }
    }

    fn between(
        scan: &LaserScan<'_>,
        sensor: &Pose2<f64>,
        a: (f64, f64),
        b: (f64, f64),
    ) -> Vec<usize> {
        let (a, b) = (Point2::new(a.0, a.1), Point2::new(b.0, b.1));
        let mut beams: Vec<usize> =
            beams_between(scan, scan.ranges.len(), sensor, &a, &b).collect();
        beams.sort_unstable();
        beams
    }

    #[test]
    fn the_beams_between_two_points_are_those_whose_bearings_lie_between_theirs() {
        // 360 beams, 1° apart from −180°: beam i looks at (i − 180)°.
        let ranges = [1.0_f32; 360];
        let scan = header(-core::f64::consts::PI, 1.0_f64.to_radians(), &ranges);
        let origin = Pose2::identity();
        let at = |deg: f64| (libm::cos(deg.to_radians()), libm::sin(deg.to_radians()));
        // 10.5° to 13.5°: beams 191..=193 and one more at each end, in either order of
        // the points.
        assert_eq!(
            between(&scan, &origin, at(10.5), at(13.5)),
            [190, 191, 192, 193, 194]
        );
        assert_eq!(
            between(&scan, &origin, at(13.5), at(10.5)),
            [190, 191, 192, 193, 194]
        );
        // Across the back (178.5° to −178.5°), the shorter way round: beams 359 (179°),
        // 0 (−180°) and 1 (−179°), and 358 and 2 next to them.
        assert_eq!(
            between(&scan, &origin, at(178.5), at(-178.5)),
            [0, 1, 2, 358, 359]
        );
        // From a sensor turned by 90°, the bearings are 90° less.
        let turned = Pose2::new(0.0, 0.0, core::f64::consts::FRAC_PI_2);
        assert_eq!(
            between(&scan, &turned, at(100.5), at(103.5)),
            [190, 191, 192, 193, 194]
        );
    }

    #[test]
    fn the_approximate_atan2_is_within_its_bound_all_round() {
        let mut worst = 0.0_f64;
        for k in 0..100_000 {
            let angle = -core::f64::consts::PI + k as f64 * core::f64::consts::TAU / 100_000.0;
            for r in [1e-3, 1.0, 70.0] {
                let (y, x) = (r * libm::sin(angle), r * libm::cos(angle));
                worst = worst.max(libm::fabs(wrap_angle(
                    atan2_approx(y, x) - libm::atan2(y, x),
                )));
            }
        }
        assert!(worst < 2e-5, "{worst}");
        assert_eq!(atan2_approx(0.0, 0.0), 0.0);
    }

    #[test]
    fn a_scan_sweeping_clockwise_or_over_half_a_turn_has_its_beams_found_too() {
        // Beam i looks at (90 − i)°, i = 0..=180.
        let ranges = [1.0_f32; 181];
        let scan = header(
            core::f64::consts::FRAC_PI_2,
            -(1.0_f64.to_radians()),
            &ranges,
        );
        let at = |deg: f64| (libm::cos(deg.to_radians()), libm::sin(deg.to_radians()));
        let origin = Pose2::identity();
        assert_eq!(
            between(&scan, &origin, at(0.5), at(-2.5)),
            [89, 90, 91, 92, 93]
        );
        // Behind the scanner: no beam.
        assert!(between(&scan, &origin, at(150.0), at(-150.0)).is_empty());
    }

    #[test]
    fn on_a_scan_all_round_the_beam_beside_the_seam_is_the_one_across_it() {
        // Beam i looks at (i − 180)°: beam 359 (179°) is beside beam 0 (−180°).
        let ranges = [1.0_f32; 360];
        let scan = header(-core::f64::consts::PI, 1.0_f64.to_radians(), &ranges);
        let at = |deg: f64| (libm::cos(deg.to_radians()), libm::sin(deg.to_radians()));
        let origin = Pose2::identity();
        // 178.5° to 179.5°: beam 359, with 358 before it and 0 after it.
        assert_eq!(between(&scan, &origin, at(178.5), at(179.5)), [0, 358, 359]);
        // From exactly −180° to −179.5°: beam 0, with 359 before it and 1 after it.
        assert_eq!(between(&scan, &origin, at(-180.0), at(-179.5)), [0, 1, 359]);
        // A scan of less than a turn does not wrap: beam 0 looks at −180°, beam 349 at
        // 169°.
        let part = header(-core::f64::consts::PI, 1.0_f64.to_radians(), &ranges[..350]);
        assert_eq!(between(&part, &origin, at(168.5), at(168.9)), [348, 349]);
        assert_eq!(between(&part, &origin, at(-180.0), at(-179.5)), [0, 1]);
    }

    #[test]
    fn any_finite_angle_is_reduced_to_within_a_turn() {
        let tau = core::f64::consts::TAU;
        for angle in [1e300, -1e300, 5e16, -7.3e17, 1234.5, -0.1, 0.0, tau] {
            for lo in [0.0, -core::f64::consts::PI] {
                let reduced = reduce(angle, lo);
                assert!((lo..lo + tau).contains(&reduced), "{angle} → {reduced}");
            }
        }
        // Far off, the remainder is exact: 1000 turns and 1 rad is 1 rad.
        assert!(libm::fabs(reduce(1000.0 * tau + 1.0, 0.0) - 1.0) < 1e-9);
        // A scan whose first beam is given a million turns on looks the same way.
        let ranges = [1.0_f32; 360];
        let far = header(
            -core::f64::consts::PI + 1e6 * tau,
            1.0_f64.to_radians(),
            &ranges,
        );
        let at = |deg: f64| (libm::cos(deg.to_radians()), libm::sin(deg.to_radians()));
        assert_eq!(
            between(&far, &Pose2::identity(), at(10.5), at(13.5)),
            [190, 191, 192, 193, 194]
        );
    }
}
