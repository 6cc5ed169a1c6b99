//! Polar → Cartesian conversion of the valid beams, with the beams' cos/sin cached across
//! scans of the same geometry, and the cut of the points into runs at invalid beams and
//! range gaps.

use super::moments::Moments;
use crate::LaserScan;
use alloc::vec::Vec;
use core::ops::Range;

/// A valid reading as a point: `(x, y) = ρ (cos φ, sin φ)` in the sensor frame, keeping
/// `ρ` and `(cos φ, sin φ)` for the weighted fit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct ScanPoint {
    /// x = ρ cos φ (m).
    pub x: f64,
    /// y = ρ sin φ (m).
    pub y: f64,
    /// Range ρ (m).
    pub range: f64,
    /// cos φ of the beam.
    pub cos: f64,
    /// sin φ of the beam.
    pub sin: f64,
}

/// cos/sin of every beam angle `φ_i = angle_min + i·angle_increment`, recomputed only
/// when the scan geometry (angle_min, angle_increment, number of beams) changes.
#[derive(Debug, Clone, Default)]
pub(crate) struct BeamTable {
    key: Option<(u64, u64)>,
    cos_sin: Vec<(f64, f64)>,
}

impl BeamTable {
    /// Makes the table match `scan`'s beam geometry.
    pub fn update(&mut self, scan: &LaserScan<'_>) {
        let key = (scan.angle_min.to_bits(), scan.angle_increment.to_bits());
        if self.key == Some(key) && self.cos_sin.len() == scan.ranges.len() {
            return;
        }
        self.cos_sin.clear();
        self.cos_sin.extend((0..scan.ranges.len()).map(|i| {
            let (s, c) = libm::sincos(scan.beam_angle(i));
            (c, s)
        }));
        self.key = Some(key);
    }
}

/// A maximal stretch of consecutive valid beams whose neighbouring points are at most
/// `max_gap` apart: `points[start..end]`.
pub(crate) type Run = Range<usize>;

/// The valid points of a scan, cut into runs, with prefix sums of their moments.
#[derive(Debug, Clone, Default)]
pub(crate) struct ScanPoints {
    /// The points in beam order.
    pub points: Vec<ScanPoint>,
    /// Runs of points, in order, tiling `points`.
    pub runs: Vec<Run>,
    /// `sums[i]`: moments of points `0..i`, each relative to the first point of its run,
    /// so `sums[j] − sums[i]` gives the moments of `i..j` within one run in O(1).
    pub sums: Vec<Moments>,
}

impl ScanPoints {
    /// The total-least-squares line `(r, ψ)` of `points[range]`, a stretch inside `run`,
    /// from the prefix sums in O(1).
    pub fn line(&self, run: &Run, range: Range<usize>) -> Option<(f64, f64)> {
        let origin = self.points.get(run.start)?;
        self.moments(range)?.line((origin.x, origin.y))
    }

    /// The moments of `points[range]`, a stretch inside one run, in O(1).
    pub fn moments(&self, range: Range<usize>) -> Option<Moments> {
        Some(*self.sums.get(range.end)? - *self.sums.get(range.start)?)
    }
}

/// Refills `out` with the valid readings of `scan` (in beam order) as points, cut into
/// runs at every invalid beam and wherever consecutive points are more than `max_gap`
/// apart. `table` must be up to date for `scan`.
pub(crate) fn collect(scan: &LaserScan<'_>, table: &BeamTable, max_gap: f64, out: &mut ScanPoints) {
    let ScanPoints { points, runs, sums } = out;
    points.clear();
    runs.clear();
    points.reserve(scan.ranges.len());
    let max_gap_sq = max_gap * max_gap;
    let mut run_start = 0;
    // The previous beam's point, if that beam was valid.
    let mut previous: Option<(f64, f64)> = None;
    let valid = ValidRanges::of(scan);
    for (&r, &(c, s)) in scan.ranges.iter().zip(&table.cos_sin) {
        let range = f64::from(r);
        if !valid.contains(range) {
            previous = None;
            continue;
        }
        let (x, y) = (range * c, range * s);
        let joins = previous.is_some_and(|(px, py)| {
            let (dx, dy) = (x - px, y - py);
            dx * dx + dy * dy <= max_gap_sq
        });
        if !joins {
            close_run(runs, run_start, points.len());
            run_start = points.len();
        }
        points.push(ScanPoint {
            x,
            y,
            range,
            cos: c,
            sin: s,
        });
        previous = Some((x, y));
    }
    close_run(runs, run_start, points.len());
    prefix_sums(points, runs, sums);
}

/// Fills `sums` with the prefix sums of the moments of `points`, each point relative to
/// the first point of its run: `sums[i]` covers `points[..i]`. A loop of its own, over
/// preallocated slots, keeps the running sum in registers.
fn prefix_sums(points: &[ScanPoint], runs: &[Run], sums: &mut Vec<Moments>) {
    sums.clear();
    sums.resize(points.len() + 1, Moments::default());
    let mut sum = Moments::default();
    for run in runs {
        let (Some(run_points), Some(slots)) = (
            points.get(run.clone()),
            sums.get_mut(run.start + 1..run.end + 1),
        ) else {
            continue;
        };
        let (ox, oy) = run_points.first().map_or((0.0, 0.0), |o| (o.x, o.y));
        for (slot, p) in slots.iter_mut().zip(run_points) {
            sum = sum.plus(p.x - ox, p.y - oy);
            *slot = sum;
        }
    }
}

/// [`LaserScan::is_valid`] as two comparisons on the `f64` value of a reading: it is
/// valid exactly when `lower < ρ < upper`, the limits being the stricter of each limit
/// and its `float32` rounding (a NaN or infinite reading fails one of the comparisons,
/// and `upper` is finite because `range_max` is).
#[derive(Debug, Clone, Copy)]
struct ValidRanges {
    lower: f64,
    upper: f64,
}

impl ValidRanges {
    /// The limits of a validated `scan`.
    fn of(scan: &LaserScan<'_>) -> Self {
        // `range > (limit as f32)` for an `f32` range is `f64::from(range) > f64::from(limit as f32)`.
        Self {
            lower: scan.range_min.max(f64::from(scan.range_min as f32)),
            upper: scan.range_max.min(f64::from(scan.range_max as f32)),
        }
    }

    /// Whether the reading `range` (widened from `f32`) is valid.
    #[inline]
    fn contains(&self, range: f64) -> bool {
        range > self.lower && range < self.upper
    }
}

/// Squared Euclidean distance between two points (m²).
#[inline]
pub(crate) fn squared_distance(a: &ScanPoint, b: &ScanPoint) -> f64 {
    let (dx, dy) = (a.x - b.x, a.y - b.y);
    dx * dx + dy * dy
}

fn close_run(runs: &mut Vec<Run>, start: usize, end: usize) {
    if end > start {
        runs.push(start..end);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn runs_break_at_invalid_beams_and_gaps() {
        let ranges = [1.0, 1.0, f32::NAN, 1.0, 1.0, 3.0, 3.0, 0.0];
        let scan = LaserScan {
            angle_min: 0.0,
            angle_increment: 0.01,
            range_min: 0.05,
            range_max: 10.0,
            ranges: &ranges,
        };
        let mut table = BeamTable::default();
        table.update(&scan);
        let mut out = ScanPoints::default();
        collect(&scan, &table, 0.3, &mut out);
        assert_eq!(out.points.len(), 6);
        assert_eq!(out.runs, [0..2, 2..4, 4..6]);
        assert_eq!(out.sums.len(), 7);
        let p = out.points[5];
        assert!((p.x - 3.0 * 0.06_f64.cos()).abs() < 1e-6);
        assert!((p.y - 3.0 * 0.06_f64.sin()).abs() < 1e-6);
        // The last run is two points at 3 m, 0.01 rad apart: its line from the sums.
        let (r, psi) = out.line(&out.runs[2].clone(), 4..6).unwrap();
        assert!((psi - 0.055).abs() < 1e-6 && (r - 3.0 * 0.005_f64.cos()).abs() < 1e-6);
    }
}
