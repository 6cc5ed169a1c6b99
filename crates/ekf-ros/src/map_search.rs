//! A coarse rigid transform between two line maps of the same place from any start, for
//! `ekf map compare --align`, whose ICP ([`crate::map_compare::align`]) converges only
//! from within about 1 m and 10°.
//!
//! The rotation comes from the walls' directions: the length-weighted histograms of the
//! two maps' wall directions (modulo 180°, 1° bins) are correlated, and the best shift
//! and its three quarter turns are the candidates (a building's walls often run in two
//! perpendicular directions, which a histogram cannot tell apart). For each, the
//! translation is searched exhaustively on a grid: points along the map's walls, turned,
//! score 2 on a cell a reference wall crosses and 1 next to one, for every offset that
//! overlaps the maps. The candidate with the highest score wins. The grid's cell is
//! 0.5 m, coarser for maps so large that the offsets would exceed a million.

use crate::map_compare::{align, compare, CompareParams, MapComparison};
use ekf_core::Pose2;
use lrf_lines::LineMap;
use nalgebra::Point2;
use std::f64::consts::PI;

/// Cell of the translation search's grid (m): the ICP that follows converges from
/// within 1 m ...
const CELL: f64 = 0.5;
/// ... unless the offsets to try would be more than this many: then the cell grows.
const MAX_OFFSETS: f64 = 1e6;
/// Points along the map's walls are taken every this (m) ...
const SAMPLE_STEP: f64 = 0.25;
/// ... at most this many (every n-th kept).
const MAX_SAMPLES: usize = 400;

/// The comparison `ekf map compare --align` reports: after the ICP
/// ([`crate::map_compare::align`]) from the identity and from the coarse transform, the
/// one of the two under which more of the reference's wall length is matched. The ICP
/// from the identity alone is not enough even where the coarse transform is within its
/// first reach (1 m, 10°): a csail SLAM map turned 9.9° from the reference came out
/// matched 0.3 % from the identity and 60 % from the coarse transform.
pub fn aligned_comparison(
    map: &LineMap,
    reference: &LineMap,
    params: &CompareParams,
) -> MapComparison {
    let identity = Pose2::new(0.0, 0.0, 0.0);
    let near = compare(map, reference, &align(map, reference, &identity), params);
    let Some(coarse) = coarse_alignment(map, reference) else {
        return near;
    };
    let far = compare(map, reference, &align(map, reference, &coarse), params);
    match far.matched_length_m > near.matched_length_m {
        true => far,
        false => near,
    }
}

/// The coarse transform moving `map` onto `reference` (see the module documentation);
/// `None` if either map has no walls.
pub fn coarse_alignment(map: &LineMap, reference: &LineMap) -> Option<Pose2<f64>> {
    let samples = samples(map);
    let occupied = Grid::of_walls(reference, &samples)?;
    let turn = best_turn(&direction_histogram(map), &direction_histogram(reference));
    (0..4)
        .map(|quarter| turn + f64::from(quarter) * PI / 2.0)
        .map(|theta| occupied.best_offset(&samples, theta))
        .max_by_key(|(_, hits)| *hits)
        .map(|(pose, _)| pose)
}

/// Points every [`SAMPLE_STEP`] along the walls, at most [`MAX_SAMPLES`] (every n-th).
fn samples(map: &LineMap) -> Vec<Point2<f64>> {
    let all = samples_every(map, SAMPLE_STEP);
    let stride = all.len().div_ceil(MAX_SAMPLES).max(1);
    all.into_iter().step_by(stride).collect()
}

/// Wall length by direction modulo 180°, in 1° bins.
fn direction_histogram(map: &LineMap) -> [f64; 180] {
    let mut bins = [0.0; 180];
    for s in &map.segments {
        let d = s.end - s.start;
        let degrees = d.y.atan2(d.x).to_degrees().rem_euclid(180.0);
        bins[(degrees as usize).min(179)] += s.length();
    }
    bins
}

/// The rotation (rad, in [0°, 180°)) that best lines `map`'s histogram up with
/// `reference`'s: the largest circular correlation `Σᵢ ref[i] · map[i − k]`, each bin
/// spread over its neighbours (±1°) so that directions split across a bin edge still
/// meet.
fn best_turn(map: &[f64; 180], reference: &[f64; 180]) -> f64 {
    let spread = |h: &[f64; 180]| -> [f64; 180] {
        std::array::from_fn(|i| h[(i + 179) % 180] + h[i] + h[(i + 1) % 180])
    };
    let (map, reference) = (spread(map), spread(reference));
    let correlation = |k: usize| -> f64 {
        (0..180)
            .map(|i| reference[i] * map[(i + 180 - k) % 180])
            .sum()
    };
    let best = (0..180)
        .max_by(|&a, &b| correlation(a).total_cmp(&correlation(b)))
        .unwrap_or(0);
    (best as f64).to_radians()
}

/// The reference's walls on a grid: 2 on a cell a wall crosses, 1 next to one, 0
/// elsewhere.
struct Grid {
    origin: Point2<f64>,
    cell: f64,
    width: usize,
    height: usize,
    score: Vec<u8>,
}

impl Grid {
    /// The grid of `reference`'s walls, its cell [`CELL`] or, if the map's `samples` could
    /// be moved to more than [`MAX_OFFSETS`] offsets over it, larger; `None` if either has
    /// no points or their extent is not finite.
    fn of_walls(reference: &LineMap, samples: &[Point2<f64>]) -> Option<Self> {
        // A wall lies within the box of its ends: no need to sample it for the bounds.
        let ends: Vec<Point2<f64>> = reference
            .segments
            .iter()
            .flat_map(|s| [s.start, s.end])
            .collect();
        let (low, high) = bounds(&ends)?;
        let (map_low, map_high) = bounds(samples)?;
        // Whatever the turn, the map's points stay within its bounding box's diagonal.
        let reach = (map_high - map_low).norm();
        let span = high - low;
        let offsets = (span.x + 2.0 * reach) * (span.y + 2.0 * reach);
        if !offsets.is_finite() {
            return None;
        }
        let cell = CELL.max((offsets / MAX_OFFSETS).sqrt());
        let points = samples_every(reference, cell / 2.0);
        let origin = low - nalgebra::Vector2::new(cell, cell);
        let width = (span.x / cell).ceil() as usize + 3;
        let height = (span.y / cell).ceil() as usize + 3;
        let mut score = vec![0u8; width * height];
        for p in &points {
            let (cx, cy) = (
                ((p.x - origin.x) / cell) as usize,
                ((p.y - origin.y) / cell) as usize,
            );
            for y in cy.saturating_sub(1)..=(cy + 1).min(height - 1) {
                for x in cx.saturating_sub(1)..=(cx + 1).min(width - 1) {
                    let s = &mut score[y * width + x];
                    *s = (*s).max(1 + u8::from(x == cx && y == cy));
                }
            }
        }
        Some(Self {
            origin,
            cell,
            width,
            height,
            score,
        })
    }

    /// The translation, in whole cells, under which `points` turned by `theta` score
    /// highest, as a pose with that heading; and the score.
    fn best_offset(&self, points: &[Point2<f64>], theta: f64) -> (Pose2<f64>, usize) {
        let cell = self.cell;
        let turn = Pose2::new(0.0, 0.0, theta);
        // Each turned point as a cell offset from the grid's origin.
        let cells: Vec<(i64, i64)> = points
            .iter()
            .map(|p| {
                let q = turn.transform_point(p);
                (
                    ((q.x - self.origin.x) / cell).floor() as i64,
                    ((q.y - self.origin.y) / cell).floor() as i64,
                )
            })
            .collect();
        let (w, h) = (self.width as i64, self.height as i64);
        // Offsets for which some point lands on the grid.
        let span = |axis: fn(&(i64, i64)) -> i64, size: i64| {
            let lo = cells.iter().map(axis).min().unwrap_or(0);
            let hi = cells.iter().map(axis).max().unwrap_or(0);
            (-hi)..(size - lo)
        };
        let mut best = ((0, 0), 0);
        for dy in span(|c| c.1, h) {
            for dx in span(|c| c.0, w) {
                let hits: usize = cells
                    .iter()
                    .map(|(x, y)| {
                        let (x, y) = (x + dx, y + dy);
                        match x >= 0 && y >= 0 && x < w && y < h {
                            true => usize::from(self.score[(y * w + x) as usize]),
                            false => 0,
                        }
                    })
                    .sum();
                if hits > best.1 {
                    best = ((dx, dy), hits);
                }
            }
        }
        let ((dx, dy), hits) = best;
        (Pose2::new(dx as f64 * cell, dy as f64 * cell, theta), hits)
    }
}

/// The lowest and highest corners of the points' bounding box; `None` for no points.
fn bounds(points: &[Point2<f64>]) -> Option<(Point2<f64>, Point2<f64>)> {
    let first = *points.first()?;
    Some(points.iter().fold((first, first), |(lo, hi), p| {
        (
            Point2::new(lo.x.min(p.x), lo.y.min(p.y)),
            Point2::new(hi.x.max(p.x), hi.y.max(p.y)),
        )
    }))
}

/// Points every `step` along the walls.
fn samples_every(map: &LineMap, step: f64) -> Vec<Point2<f64>> {
    map.segments
        .iter()
        .flat_map(|s| {
            let n = (s.length() / step).ceil().max(1.0) as usize;
            (0..=n).map(move |i| s.start + (s.end - s.start) * (i as f64 / n as f64))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::map_compare::transformed;
    use crate::test_support::{map_of, ROOM_WITH_STUB};

    /// A room and a corridor leading to a second, smaller room: no symmetry.
    fn floor() -> LineMap {
        let mut walls = ROOM_WITH_STUB.to_vec();
        walls.extend([
            [10.0, 2.0, 25.0, 2.0],
            [10.0, 4.0, 22.0, 4.0],
            [22.0, 4.0, 22.0, 12.0],
            [25.0, 2.0, 25.0, 12.0],
            [22.0, 12.0, 25.0, 12.0],
        ]);
        map_of(&walls)
    }

    #[test]
    fn a_map_turned_and_moved_far_is_found_and_aligned_exactly() {
        let reference = floor();
        for motion in [
            Pose2::new(-7.0, 13.0, 34f64.to_radians()),
            Pose2::new(20.0, -5.0, 200f64.to_radians()),
            Pose2::new(0.3, 0.2, -95f64.to_radians()),
        ] {
            let map = transformed(&reference, &motion);
            let coarse = coarse_alignment(&map, &reference).unwrap();
            let back = coarse.compose(&motion);
            assert!(
                back.x.hypot(back.y) < 0.6 && ekf_core::angle_diff(back.theta, 0.0).abs() < 0.03,
                "{motion:?}: coarse {coarse:?}, residual {back:?}"
            );
            let fine = align(&map, &reference, &coarse);
            let c = compare(&map, &reference, &fine, &CompareParams::default());
            assert!(c.matched_share > 0.999, "{motion:?}: {c:?}");
        }
    }

    #[test]
    fn a_map_against_itself_stays_where_it_is() {
        let floor = floor();
        assert_eq!(
            coarse_alignment(&floor, &floor),
            Some(Pose2::new(0.0, 0.0, 0.0))
        );
        let c = aligned_comparison(&floor, &floor, &CompareParams::default());
        assert!(c.alignment.iter().all(|v| v.abs() < 1e-9), "{c:?}");
        assert!(c.matched_share > 0.999, "{c:?}");
    }

    #[test]
    fn a_map_far_from_the_reference_is_compared_where_it_belongs() {
        let reference = floor();
        let map = transformed(&reference, &Pose2::new(30.0, -12.0, 123f64.to_radians()));
        let c = aligned_comparison(&map, &reference, &CompareParams::default());
        assert!(c.matched_share > 0.999, "{c:?}");
        // From the identity alone the ICP finds nothing.
        let near = compare(
            &map,
            &reference,
            &align(&map, &reference, &Pose2::new(0.0, 0.0, 0.0)),
            &CompareParams::default(),
        );
        assert!(near.matched_share < 0.2, "{near:?}");
    }

    #[test]
    fn direction_histograms_line_up_at_the_turn_between_them() {
        let reference = floor();
        let map = transformed(&reference, &Pose2::new(0.0, 0.0, 34f64.to_radians()));
        let turn = best_turn(&direction_histogram(&map), &direction_histogram(&reference));
        // 34° back is 146° modulo 180°, or 56° modulo 90°.
        let degrees = turn.to_degrees().round() as i64;
        assert_eq!(degrees % 90, 56, "{degrees}");
    }

    #[test]
    fn an_empty_map_has_no_alignment() {
        assert_eq!(coarse_alignment(&LineMap::default(), &floor()), None);
        assert_eq!(coarse_alignment(&floor(), &LineMap::default()), None);
    }
}
