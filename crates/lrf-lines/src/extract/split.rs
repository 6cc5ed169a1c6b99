//! The split step of split-and-merge (iterative end-point fit): a run of points is cut at
//! the point farthest from the chord between its end points until every piece is straight.

use super::moments::NormalLine;
use super::points::{Points, Run, ScanPoints};
use alloc::vec::Vec;
use core::ops::Range;

/// Splits every run of `scan` into straight segments, appended to `segments` in scan
/// order. A range `points[s..e]` is split at `k`, the point with the largest distance
/// `|n·(p_k − p_s)|` from the chord `p_s → p_{e−1}` (`n` its unit normal), when that
/// distance exceeds `split_distance`; the pieces are `s..k` and `k+1..e` (the split
/// point, usually a corner, is in neither), after [`refine_split`] has moved `k` to where
/// the points change sides. Pieces with fewer than `min_points` points are dropped.
/// `stack` is scratch space (an explicit stack instead of recursion).
pub(crate) fn split_runs(
    scan: &ScanPoints,
    points: &Points<'_>,
    split_distance: f64,
    min_points: usize,
    stack: &mut Vec<Run>,
    segments: &mut Vec<Run>,
) {
    for run in &scan.runs {
        stack.clear();
        stack.push(run.clone());
        while let Some(range) = stack.pop() {
            if range.len() < min_points {
                continue;
            }
            match farthest_from_chord(points, range.clone()) {
                Some((k, d)) if d > split_distance => {
                    let k = refine_split(scan, points, run, range.clone(), k, split_distance);
                    // Right piece first so the left one is popped (and emitted) first.
                    stack.push(k + 1..range.end);
                    stack.push(range.start..k);
                }
                _ => segments.push(range),
            }
        }
    }
}

/// Moves the split point `k` of `range` (inside `run`) to where the points change from
/// being nearer the total-least-squares line of `range.start..k` to being nearer that of
/// `k+1..range.end` (both from the prefix sums, O(1)). The farthest point from a chord is
/// only near a corner as far as the noise allows; left alone, a few points of one wall
/// end up at the end of the other and bias its fit. Each piece keeps at least half its
/// points.
fn refine_split(
    scan: &ScanPoints,
    points: &Points<'_>,
    run: &Run,
    range: Range<usize>,
    k: usize,
    split_distance: f64,
) -> usize {
    // Only between two pieces that are already lines; a piece still holding a corner
    // has a meaningless total-least-squares line.
    let straight = |r: Range<usize>| {
        scan.moments(r).is_some_and(|m| {
            m.mean_squared_residual() <= STRAIGHT_FRACTION * split_distance * split_distance
        })
    };
    if !straight(range.start..k) || !straight(k + 1..range.end) {
        return k;
    }
    let (Some(left), Some(right)) = (
        scan.line(run, range.start..k),
        scan.line(run, k + 1..range.end),
    ) else {
        return k;
    };
    let nearer = |i: usize, to: NormalLine, other: NormalLine| {
        points
            .xy(i)
            .is_some_and(|p| distance(p, to) < distance(p, other))
    };
    let lowest = range.start + (k - range.start).div_ceil(2);
    let highest = range.end - (range.end - k - 1).div_ceil(2);
    let mut split = k;
    while split > lowest && nearer(split - 1, right, left) {
        split -= 1;
    }
    if split == k {
        while split + 1 < highest && nearer(split + 1, left, right) {
            split += 1;
        }
    }
    split
}

/// A piece counts as straight for [`refine_split`] when its mean squared residual is
/// below this fraction of `split_distance²` (rms below a third of it).
const STRAIGHT_FRACTION: f64 = 1.0 / 9.0;

/// Unsigned distance of a point from a line.
fn distance((x, y): (f64, f64), line: NormalLine) -> f64 {
    libm::fabs(x * line.cos + y * line.sin - line.r)
}

/// Beam and distance of the point of `range` farthest from the chord through its first
/// and last points. For coincident end points the distance is measured from the first
/// point. `None` for fewer than three points.
fn farthest_from_chord(points: &Points<'_>, range: Range<usize>) -> Option<(usize, f64)> {
    if range.len() < 3 {
        return None;
    }
    let (xs, ys) = (points.x.get(range.clone())?, points.y.get(range.clone())?);
    let (fx, fy, lx, ly) = (*xs.first()?, *ys.first()?, *xs.last()?, *ys.last()?);
    let (dx, dy) = (lx - fx, ly - fy);
    let len = libm::sqrt(dx * dx + dy * dy);
    let mut best = (0, 0.0);
    if len > 0.0 {
        let (nx, ny) = (-dy / len, dx / len);
        let distance = |x: f64, y: f64| libm::fabs(nx * (x - fx) + ny * (y - fy));
        // Two points per iteration: half the loop overhead, and room for the compiler to
        // interleave the two distances.
        let (x_pairs, y_pairs) = (xs.chunks_exact(2), ys.chunks_exact(2));
        let last = x_pairs.remainder().first().zip(y_pairs.remainder().first());
        for (pair, (x, y)) in x_pairs.zip(y_pairs).enumerate() {
            let (Some(&[x0, x1]), Some(&[y0, y1])) = (x.first_chunk(), y.first_chunk()) else {
                continue;
            };
            let (d0, d1) = (distance(x0, y0), distance(x1, y1));
            if d0 > best.1 {
                best = (2 * pair, d0);
            }
            if d1 > best.1 {
                best = (2 * pair + 1, d1);
            }
        }
        if let Some((&x, &y)) = last {
            let d = distance(x, y);
            if d > best.1 {
                best = (xs.len() - 1, d);
            }
        }
    } else {
        for (i, (&x, &y)) in xs.iter().zip(ys).enumerate() {
            let d = libm::hypot(x - fx, y - fy);
            if d > best.1 {
                best = (i, d);
            }
        }
    }
    Some((range.start + best.0, best.1))
}

#[cfg(test)]
mod tests {
    use super::super::points::testing::TestScan;
    use super::*;

    #[test]
    fn splits_a_corner_and_keeps_order() {
        // An L: 10 points along the wall y = 2 (x from 3 down to 0.3), then 10 along the
        // wall x = −0.3 (y from 2 down to −0.25).
        let mut points: Vec<(f64, f64)> = (0..10).map(|i| (3.0 - 0.3 * i as f64, 2.0)).collect();
        points.extend((0..10).map(|i| (-0.3, 2.0 - 0.25 * i as f64)));
        let test = TestScan::xy(points, core::slice::from_ref(&(0..20)));
        let points = test.points();
        let (mut stack, mut segments) = (Vec::new(), Vec::new());
        split_runs(&test.scan, &points, 0.05, 3, &mut stack, &mut segments);
        assert_eq!(segments.len(), 2, "{segments:?}");
        assert!(segments[0].end <= segments[1].start);
        for s in &segments {
            assert!(farthest_from_chord(&points, s.clone()).unwrap().1 <= 0.05);
        }
    }

    #[test]
    fn short_and_degenerate_runs() {
        let test = TestScan::xy(
            [(1.0, 0.0), (1.0, 0.0), (1.0, 0.0), (2.0, 0.0)],
            &[0..3, 3..4],
        );
        let points = test.points();
        let (mut stack, mut segments) = (Vec::new(), Vec::new());
        split_runs(&test.scan, &points, 0.05, 2, &mut stack, &mut segments);
        assert_eq!(segments.len(), 1);
        assert_eq!(segments[0], 0..3);
        assert_eq!(farthest_from_chord(&points, 0..2), None);
    }
}
