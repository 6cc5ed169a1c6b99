//! A coarse rigid transform between two line maps of the same place from any start, for
//! `ekf map compare --align`, whose ICP ([`crate::map_compare::align`]) converges only
//! from within about 1 m and 10°.
//!
//! The rotation comes from the walls' directions: the length-weighted histograms of the
//! two maps' wall directions (modulo 180°, 1° bins) are correlated, and the best shift
//! and its three quarter turns are the candidates (a building's walls often run in two
//! perpendicular directions, which a histogram cannot tell apart). For each, the
//! translation is searched exhaustively on a grid: points along the map's walls, turned,
//! are counted where they fall on cells the reference's walls cross (dilated by one
//! cell), for every offset that overlaps the maps. The candidate with the most points on
//! walls wins.

use crate::map_compare::{align, compare, CompareParams};
use ekf_core::{angle_diff, Pose2};
use lrf_lines::LineMap;
use nalgebra::Point2;
use std::f64::consts::PI;

/// Cell of the translation search's grid (m): the ICP that follows converges from
/// within 1 m.
const CELL: f64 = 0.5;
/// Points along the map's walls are taken every this (m) ...
const SAMPLE_STEP: f64 = 0.25;
/// ... at most this many (every n-th kept).
const MAX_SAMPLES: usize = 400;

/// The transform `ekf map compare --align` applies: the ICP
/// ([`crate::map_compare::align`]) from the identity and, when the coarse search puts the
/// map beyond the ICP's first reach (1 m, 10°), also from the coarse transform; of the
/// two, the one under which more of the reference's wall length is matched.
pub fn alignment(map: &LineMap, reference: &LineMap, params: &CompareParams) -> Pose2<f64> {
    let identity = Pose2::new(0.0, 0.0, 0.0);
    let near = align(map, reference, &identity);
    let Some(coarse) = coarse_alignment(map, reference)
        .filter(|c| c.x.hypot(c.y) > 1.0 || angle_diff(c.theta, 0.0).abs() > 10f64.to_radians())
    else {
        return near;
    };
    let far = align(map, reference, &coarse);
    let matched = |pose: &Pose2<f64>| compare(map, reference, pose, params).matched_length_m;
    match matched(&far) > matched(&near) {
        true => far,
        false => near,
    }
}

/// The coarse transform moving `map` onto `reference` (see the module documentation);
/// `None` if either map has no walls.
pub fn coarse_alignment(map: &LineMap, reference: &LineMap) -> Option<Pose2<f64>> {
    let samples = samples(map);
    let occupied = Grid::of_walls(reference)?;
    if samples.is_empty() {
        return None;
    }
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

/// The cells of [`CELL`] that the reference's walls cross, dilated by one cell.
struct Grid {
    origin: Point2<f64>,
    width: usize,
    height: usize,
    occupied: Vec<bool>,
}

impl Grid {
    /// `None` for a map without walls.
    fn of_walls(map: &LineMap) -> Option<Self> {
        let points = samples_every(map, CELL / 2.0);
        let min_x = points.iter().map(|p| p.x).reduce(f64::min)?;
        let min_y = points.iter().map(|p| p.y).reduce(f64::min)?;
        let max_x = points.iter().map(|p| p.x).reduce(f64::max)?;
        let max_y = points.iter().map(|p| p.y).reduce(f64::max)?;
        let origin = Point2::new(min_x - CELL, min_y - CELL);
        let width = ((max_x - min_x) / CELL).ceil() as usize + 3;
        let height = ((max_y - min_y) / CELL).ceil() as usize + 3;
        let mut occupied = vec![false; width * height];
        for p in &points {
            let (cx, cy) = (
                ((p.x - origin.x) / CELL) as usize,
                ((p.y - origin.y) / CELL) as usize,
            );
            for y in cy.saturating_sub(1)..=(cy + 1).min(height - 1) {
                for x in cx.saturating_sub(1)..=(cx + 1).min(width - 1) {
                    occupied[y * width + x] = true;
                }
            }
        }
        Some(Self {
            origin,
            width,
            height,
            occupied,
        })
    }

    /// The translation, in whole cells, that puts the most of `points` turned by `theta`
    /// on occupied cells, as a pose with that heading; and how many it puts there.
    fn best_offset(&self, points: &[Point2<f64>], theta: f64) -> (Pose2<f64>, usize) {
        let turn = Pose2::new(0.0, 0.0, theta);
        // Each turned point as a cell offset from the grid's origin.
        let cells: Vec<(i64, i64)> = points
            .iter()
            .map(|p| {
                let q = turn.transform_point(p);
                (
                    ((q.x - self.origin.x) / CELL).floor() as i64,
                    ((q.y - self.origin.y) / CELL).floor() as i64,
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
                let hits = cells
                    .iter()
                    .filter(|(x, y)| {
                        let (x, y) = (x + dx, y + dy);
                        x >= 0 && y >= 0 && x < w && y < h && self.occupied[(y * w + x) as usize]
                    })
                    .count();
                if hits > best.1 {
                    best = ((dx, dy), hits);
                }
            }
        }
        let ((dx, dy), hits) = best;
        (Pose2::new(dx as f64 * CELL, dy as f64 * CELL, theta), hits)
    }
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
    use crate::test_support::{map_of, ROOM};

    /// A room and a corridor leading to a second, smaller room: no symmetry.
    fn floor() -> LineMap {
        let mut walls = ROOM.to_vec();
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
                back.x.hypot(back.y) < 1.0 && ekf_core::angle_diff(back.theta, 0.0).abs() < 0.05,
                "{motion:?}: coarse {coarse:?}, residual {back:?}"
            );
            let fine = align(&map, &reference, &coarse);
            let c = compare(&map, &reference, &fine, &CompareParams::default());
            assert!(c.matched_share > 0.999, "{motion:?}: {c:?}");
        }
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
