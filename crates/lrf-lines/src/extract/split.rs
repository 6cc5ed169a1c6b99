//! The split step of split-and-merge (iterative end-point fit): a run of points is cut at
//! the point farthest from the chord between its end points until every piece is straight.

use super::points::{Run, ScanPoint};
use alloc::vec::Vec;

/// Splits every run in `runs` into straight segments, appended to `segments` in scan
/// order. A range `points[s..e]` is split at `k`, the point with the largest distance
/// `|n·(p_k − p_s)|` from the chord `p_s → p_{e−1}` (`n` its unit normal), when that
/// distance exceeds `split_distance`; the pieces are `s..k` and `k+1..e` (the split
/// point, usually a corner, is in neither). Pieces with fewer than `min_points` points
/// are dropped. `stack` is scratch space (an explicit stack instead of recursion).
pub(crate) fn split_runs(
    points: &[ScanPoint],
    runs: &[Run],
    split_distance: f64,
    min_points: usize,
    stack: &mut Vec<Run>,
    segments: &mut Vec<Run>,
) {
    for run in runs {
        stack.clear();
        stack.push(run.clone());
        while let Some(range) = stack.pop() {
            if range.len() < min_points {
                continue;
            }
            let Some(seg) = points.get(range.clone()) else {
                continue;
            };
            match farthest_from_chord(seg) {
                Some((k, d)) if d > split_distance => {
                    // Right piece first so the left one is popped (and emitted) first.
                    stack.push(range.start + k + 1..range.end);
                    stack.push(range.start..range.start + k);
                }
                _ => segments.push(range),
            }
        }
    }
}

/// Index (within `seg`) and distance of the point farthest from the chord through the
/// first and last points. For coincident end points the distance is measured from the
/// first point. `None` for fewer than three points.
fn farthest_from_chord(seg: &[ScanPoint]) -> Option<(usize, f64)> {
    let (first, last) = (seg.first()?, seg.last()?);
    if seg.len() < 3 {
        return None;
    }
    let (dx, dy) = (last.x - first.x, last.y - first.y);
    let len = libm::sqrt(dx * dx + dy * dy);
    let mut best = (0, 0.0);
    if len > 0.0 {
        let (nx, ny) = (-dy / len, dx / len);
        for (i, p) in seg.iter().enumerate() {
            let d = libm::fabs(nx * (p.x - first.x) + ny * (p.y - first.y));
            if d > best.1 {
                best = (i, d);
            }
        }
    } else {
        for (i, p) in seg.iter().enumerate() {
            let d = libm::hypot(p.x - first.x, p.y - first.y);
            if d > best.1 {
                best = (i, d);
            }
        }
    }
    Some(best)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pt(x: f64, y: f64) -> ScanPoint {
        let range = libm::hypot(x, y);
        ScanPoint {
            x,
            y,
            range,
            cos: x / range,
            sin: y / range,
        }
    }

    #[test]
    fn splits_a_corner_and_keeps_order() {
        // An L: 10 points along the wall y = 2 (x from 3 down to 0.3), then 10 along the
        // wall x = −0.3 (y from 2 down to −0.25).
        let mut points: Vec<ScanPoint> = (0..10).map(|i| pt(3.0 - 0.3 * i as f64, 2.0)).collect();
        points.extend((0..10).map(|i| pt(-0.3, 2.0 - 0.25 * i as f64)));
        let (mut stack, mut segments) = (Vec::new(), Vec::new());
        let whole = [Run { start: 0, end: 20 }];
        split_runs(&points, &whole, 0.05, 3, &mut stack, &mut segments);
        assert_eq!(segments.len(), 2, "{segments:?}");
        assert!(segments[0].end <= segments[1].start);
        for s in &segments {
            assert!(farthest_from_chord(&points[s.clone()]).unwrap().1 <= 0.05);
        }
    }

    #[test]
    fn short_and_degenerate_runs() {
        let points = [pt(1.0, 0.0), pt(1.0, 0.0), pt(1.0, 0.0)];
        let (mut stack, mut segments) = (Vec::new(), Vec::new());
        split_runs(&points, &[0..3, 0..1], 0.05, 2, &mut stack, &mut segments);
        assert_eq!(segments.len(), 1);
        assert_eq!(segments[0], 0..3);
        assert_eq!(farthest_from_chord(&points[..2]), None);
    }
}
