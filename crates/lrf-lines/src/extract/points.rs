//! Polar → Cartesian conversion of the beams into arrays indexed by beam (structure of
//! arrays), with the beams' cos/sin cached across scans of the same geometry, and the cut
//! of the valid points into runs at invalid beams and range gaps. The later steps address
//! points by beam, so nothing is copied between them.

use super::breakpoint::Breakpoint;
use super::moments::{Moments, NormalLine};
use crate::LaserScan;
use alloc::vec::Vec;
use core::ops::Range;

/// cos/sin of every beam angle `φ_i = angle_min + i·angle_increment`, recomputed only
/// when the scan geometry (angle_min, angle_increment, number of beams) changes.
#[derive(Debug, Clone, Default)]
pub(crate) struct BeamTable {
    key: Option<(u64, u64)>,
    cos: Vec<f64>,
    sin: Vec<f64>,
}

impl BeamTable {
    /// `(cos φ_i, sin φ_i)` of every beam.
    pub fn directions(&self) -> (&[f64], &[f64]) {
        (&self.cos, &self.sin)
    }

    /// Makes the table match `scan`'s beam geometry.
    pub fn update(&mut self, scan: &LaserScan<'_>) {
        let key = (scan.angle_min.to_bits(), scan.angle_increment.to_bits());
        if self.key == Some(key) && self.cos.len() == scan.ranges.len() {
            return;
        }
        self.cos.clear();
        self.sin.clear();
        for i in 0..scan.ranges.len() {
            let (s, c) = libm::sincos(scan.beam_angle(i));
            self.cos.push(c);
            self.sin.push(s);
        }
        self.key = Some(key);
    }
}

/// A maximal stretch of consecutive valid beams whose neighbouring points are no farther
/// apart than the [`Breakpoint`] rule allows: beams `start..end`.
pub(crate) type Run = Range<usize>;

/// The points of a scan, indexed by beam, as parallel slices (structure of arrays: each
/// per-point loop loads only the fields it uses, and the conversion loop vectorises).
/// Only beams inside a run are valid points; the entries of the other beams are
/// meaningless.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Points<'a> {
    /// x = ρ cos φ (m).
    pub x: &'a [f64],
    /// y = ρ sin φ (m).
    pub y: &'a [f64],
    /// Range ρ (m).
    pub range: &'a [f64],
    /// cos φ of the beam.
    pub cos: &'a [f64],
    /// sin φ of the beam.
    pub sin: &'a [f64],
}

impl Points<'_> {
    /// The point of beam `i` as `(x, y)`.
    #[inline]
    pub fn xy(&self, i: usize) -> Option<(f64, f64)> {
        Some((*self.x.get(i)?, *self.y.get(i)?))
    }
}

/// The points of a scan (see [`Points`]), cut into runs, with prefix sums of their
/// moments.
#[derive(Debug, Clone, Default)]
pub(crate) struct ScanPoints {
    /// x of every beam's point (m).
    x: Vec<f64>,
    /// y of every beam's point (m).
    y: Vec<f64>,
    /// Every beam's range ρ (m).
    range: Vec<f64>,
    /// `gap_sq[i]` for `i ≥ 1`: squared distance between the points of beams `i − 1` and
    /// `i` (m²); `gap_sq[0]` is not used.
    gap_sq: Vec<f64>,
    /// Runs of valid points, in beam order.
    pub runs: Vec<Run>,
    /// `sums[i]` for `i` in `run.start..=run.end` of each run: moments of all the run
    /// points before beam `i`, each relative to the first point of its run, so
    /// `sums[j] − sums[i]` gives the moments of `i..j` within one run in O(1).
    sums: Vec<Moments>,
}

impl ScanPoints {
    /// The points, with the beams' cos/sin from `table` (the one they were collected with).
    pub fn points<'a>(&'a self, table: &'a BeamTable) -> Points<'a> {
        Points {
            x: &self.x,
            y: &self.y,
            range: &self.range,
            cos: &table.cos,
            sin: &table.sin,
        }
    }

    /// The total-least-squares line of the points `range`, a stretch inside `run`, from
    /// the prefix sums in O(1).
    pub fn line(&self, run: &Run, range: Range<usize>) -> Option<NormalLine> {
        let origin = (*self.x.get(run.start)?, *self.y.get(run.start)?);
        self.moments(range)?.line(origin)
    }

    /// The moments of the points `range`, a stretch inside one run, in O(1).
    pub fn moments(&self, range: Range<usize>) -> Option<Moments> {
        let sums = *self.sums.get(range.end)? - *self.sums.get(range.start)?;
        Some(sums.with_count(range.len()))
    }
}

/// Refills `out` with the readings of `scan` as points, and cuts the valid ones (in beam
/// order) into runs at every invalid beam and wherever consecutive points are farther
/// apart than `breakpoint` allows. `table` must be up to date for `scan`.
pub(crate) fn collect(
    scan: &LaserScan<'_>,
    table: &BeamTable,
    breakpoint: &Breakpoint,
    out: &mut ScanPoints,
) {
    let ScanPoints {
        x,
        y,
        range,
        gap_sq,
        runs,
        sums,
    } = out;
    // Every beam, valid or not, in loops without branches, which vectorise. Every slot
    // is overwritten, so the buffers are only resized (usually a no-op), not cleared.
    let n = scan.ranges.len().min(table.cos.len()).min(table.sin.len());
    for v in [&mut *x, &mut *y, &mut *range, &mut *gap_sq] {
        v.resize(n, 0.0);
    }
    let polar = scan.ranges.iter().zip(&table.cos).zip(&table.sin);
    let cartesian = x.iter_mut().zip(y.iter_mut()).zip(range.iter_mut());
    for (((x, y), rho), ((&r, &c), &s)) in cartesian.zip(polar) {
        let r = f64::from(r);
        *rho = r;
        *x = r * c;
        *y = r * s;
    }
    // gap_sq[i]: squared distance from the point of beam i − 1 to that of beam i.
    let (next, previous) = (x.iter().zip(y.iter()).skip(1), x.iter().zip(y.iter()));
    for (g, ((&x, &y), (&px, &py))) in gap_sq.iter_mut().skip(1).zip(next.zip(previous)) {
        let (dx, dy) = (x - px, y - py);
        *g = dx * dx + dy * dy;
    }
    runs.clear();
    let valid = ValidRanges::of(scan);
    // The first beam of the current run, if the previous beam was valid, and that
    // beam's range.
    let mut run_start: Option<usize> = None;
    let mut previous_range = 0.0;
    for (i, (&r, &gap)) in range.iter().zip(gap_sq.iter()).enumerate() {
        if !valid.contains(r) {
            if let Some(start) = run_start.take() {
                runs.push(start..i);
            }
            continue;
        }
        // Both points are valid, hence finite, and so is `gap`.
        let limit = breakpoint.max_gap(previous_range, r);
        match run_start {
            Some(start) if gap > limit * limit => {
                runs.push(start..i);
                run_start = Some(i);
            }
            Some(_) => {}
            None => run_start = Some(i),
        }
        previous_range = r;
    }
    if let Some(start) = run_start {
        runs.push(start..n);
    }
    prefix_sums(x, y, runs, sums);
}

/// Fills `sums` with the prefix sums of the moments of the points in `runs`, each point
/// relative to the first point of its run: `sums[i]` (for `i` in `run.start..=run.end`)
/// covers the points before beam `i`; the other slots are left as they were (they are
/// never read). A loop of its own, over preallocated slots, keeps the running sum in
/// registers.
fn prefix_sums(x: &[f64], y: &[f64], runs: &[Run], sums: &mut Vec<Moments>) {
    sums.resize(x.len() + 1, Moments::default());
    let mut sum = Moments::default();
    for run in runs {
        let (Some(xs), Some(ys), Some(slots)) = (
            x.get(run.clone()),
            y.get(run.clone()),
            sums.get_mut(run.start..run.end + 1),
        ) else {
            continue;
        };
        let (ox, oy) = (xs.first().copied(), ys.first().copied());
        let (ox, oy) = (ox.unwrap_or(0.0), oy.unwrap_or(0.0));
        let Some((first, slots)) = slots.split_first_mut() else {
            continue;
        };
        *first = sum;
        for ((slot, &px), &py) in slots.iter_mut().zip(xs).zip(ys) {
            sum = sum.plus(px - ox, py - oy);
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

/// Point sets for the unit tests of the pipeline's steps.
#[cfg(test)]
pub(crate) mod testing {
    use super::{prefix_sums, BeamTable, Points, Run, ScanPoints};
    use alloc::vec::Vec;

    /// Points given one per beam, cut into the given runs, with their prefix sums.
    pub(crate) struct TestScan {
        pub scan: ScanPoints,
        pub table: BeamTable,
    }

    impl TestScan {
        /// Points at `(ρ, φ)`, one run.
        pub fn polar(points: impl IntoIterator<Item = (f64, f64)>) -> Self {
            let points: Vec<_> = points.into_iter().collect();
            let n = points.len();
            Self::new(
                points
                    .into_iter()
                    .map(|(r, phi)| (r * phi.cos(), r * phi.sin(), r, phi.cos(), phi.sin())),
                core::slice::from_ref(&(0..n)),
            )
        }

        /// Points at `(x, y)`, cut into `runs`.
        pub fn xy(points: impl IntoIterator<Item = (f64, f64)>, runs: &[Run]) -> Self {
            Self::new(
                points.into_iter().map(|(x, y)| {
                    let r = x.hypot(y);
                    (x, y, r, x / r, y / r)
                }),
                runs,
            )
        }

        fn new(points: impl Iterator<Item = (f64, f64, f64, f64, f64)>, runs: &[Run]) -> Self {
            let (mut scan, mut table) = (ScanPoints::default(), BeamTable::default());
            for (x, y, r, c, s) in points {
                scan.x.push(x);
                scan.y.push(y);
                scan.range.push(r);
                table.cos.push(c);
                table.sin.push(s);
            }
            scan.runs = runs.to_vec();
            prefix_sums(&scan.x, &scan.y, &scan.runs, &mut scan.sums);
            Self { scan, table }
        }

        /// The points.
        pub fn points(&self) -> Points<'_> {
            self.scan.points(&self.table)
        }
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
        collect(
            &scan,
            &table,
            &Breakpoint::new(0.3, 0.17, 0.01, 0.01),
            &mut out,
        );
        assert_eq!(out.runs, [0..2, 3..5, 5..7]);
        assert_eq!(out.sums.len(), 9);
        let (x, y) = out.points(&table).xy(6).unwrap();
        assert!((x - 3.0 * 0.06_f64.cos()).abs() < 1e-6);
        assert!((y - 3.0 * 0.06_f64.sin()).abs() < 1e-6);
        // The last run is two points at 3 m, 0.01 rad apart: its line from the sums.
        let NormalLine { r, psi, .. } = out.line(&out.runs[2].clone(), 5..7).unwrap();
        assert!((psi - 0.055).abs() < 1e-6 && (r - 3.0 * 0.005_f64.cos()).abs() < 1e-6);
    }
}
