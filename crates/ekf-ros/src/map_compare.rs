//! `ekf map compare MAP.json --reference REF.json`: how much of a reference map's wall
//! length a map reproduces, and how much of the map has no counterpart in it — after an
//! optional rigid alignment of the map onto the reference.

use ekf_core::{angle_diff, Pose2};
use lrf_lines::map::WallIndex;
use lrf_lines::{LineMap, MapSegment};
use nalgebra::{Matrix3, Point2, Vector2, Vector3};
use serde::Serialize;

/// When a piece of one wall counts as matched by a wall of the other map.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct CompareParams {
    /// Largest distance from the piece to the other wall (m). Default 0.1.
    pub max_distance: f64,
    /// Largest angle between the walls (rad). Default 2°.
    pub max_angle: f64,
    /// Length of the pieces walls are cut into (m). Default 0.05.
    pub step: f64,
}

impl Default for CompareParams {
    fn default() -> Self {
        Self {
            max_distance: 0.1,
            max_angle: 2f64.to_radians(),
            step: 0.05,
        }
    }
}

/// The result.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MapComparison {
    /// Walls of the reference.
    pub reference_walls: usize,
    /// Walls of the map.
    pub map_walls: usize,
    /// Total wall length of the reference (m).
    pub reference_length_m: f64,
    /// Length of it matched by the map (m).
    pub matched_length_m: f64,
    /// `matched_length_m / reference_length_m`.
    pub matched_share: f64,
    /// Total wall length of the map (m).
    pub map_length_m: f64,
    /// Length of the map's walls with no counterpart in the reference (m).
    pub unmatched_map_length_m: f64,
    /// The rigid transform `[x, y, θ]` applied to the map before comparing (identity
    /// without alignment).
    pub alignment: [f64; 3],
}

/// The comparison as `ekf map compare` prints it: one line.
impl std::fmt::Display for MapComparison {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let [x, y, t] = self.alignment;
        writeln!(
            f,
            "{:.1} % of the reference's {:.1} m of walls matched ({:.1} m); {:.1} m of the map's {:.1} m without a counterpart; alignment [{x:.3} m, {y:.3} m, {:.3}°]",
            100.0 * self.matched_share,
            self.reference_length_m,
            self.matched_length_m,
            self.unmatched_map_length_m,
            self.map_length_m,
            t.to_degrees()
        )
    }
}

/// Compares `map` (moved by `alignment`) with `reference` (see [`MapComparison`]). A
/// piece of a wall (of length `step`) is matched if its middle is within `max_distance`
/// of a wall of the other map (as a segment) whose direction is within `max_angle`.
pub fn compare(
    map: &LineMap,
    reference: &LineMap,
    alignment: &Pose2<f64>,
    params: &CompareParams,
) -> MapComparison {
    let moved = transformed(map, alignment);
    let (reference_length_m, matched_length_m) = covered(reference, &moved, params);
    let (map_length_m, map_matched) = covered(&moved, reference, params);
    MapComparison {
        reference_walls: reference.len(),
        map_walls: map.len(),
        reference_length_m,
        matched_length_m,
        matched_share: if reference_length_m > 0.0 {
            matched_length_m / reference_length_m
        } else {
            0.0
        },
        map_length_m,
        unmatched_map_length_m: map_length_m - map_matched,
        alignment: [alignment.x, alignment.y, alignment.theta],
    }
}

/// The rigid transform that moves `map` onto `reference`, starting from `initial`: ICP of
/// points every 0.2 m along the map's walls to the lines of the nearest reference walls of
/// similar direction (point-to-line least squares, Gauss–Newton), first within 1 m and
/// 10°, then within 0.3 m and 5°.
pub fn align(map: &LineMap, reference: &LineMap, initial: &Pose2<f64>) -> Pose2<f64> {
    let samples: Vec<(Point2<f64>, f64)> = map
        .segments
        .iter()
        .flat_map(|s| pieces(s, 0.2).map(move |(p, _)| (p, s.line.beta)))
        .collect();
    let mut walls = Walls::of(reference);
    let mut pose = *initial;
    for (gate, angle) in [(1.0, 10f64.to_radians()), (0.3, 5f64.to_radians())] {
        for _ in 0..30 {
            let mut h = Matrix3::zeros();
            let mut g = Vector3::zeros();
            for (p, beta) in &samples {
                let q = pose.transform_point(p);
                let b = beta + pose.theta;
                let Some(wall) = walls.nearest(&q, b, gate, angle) else {
                    continue;
                };
                // r = n·q − ρ; dr/d(x, y, θ) = (n_x, n_y, n·perp(q − t)).
                let n = Vector2::new(wall.line.beta.cos(), wall.line.beta.sin());
                let r = n.dot(&q.coords) - wall.line.rho;
                let arm = q - Point2::new(pose.x, pose.y);
                let j = Vector3::new(n.x, n.y, n.dot(&Vector2::new(-arm.y, arm.x)));
                h += j * j.transpose();
                g += j * r;
            }
            let Some(step) = h.try_inverse().map(|inv| -(inv * g)) else {
                break;
            };
            // Rotate about the current position, then translate.
            pose = Pose2::new(pose.x + step.x, pose.y + step.y, pose.theta + step.z);
            if step.xy().norm() < 1e-6 && step.z.abs() < 1e-7 {
                break;
            }
        }
    }
    pose
}

/// The total length of `of`'s walls and the part of it within reach of `by`'s.
fn covered(of: &LineMap, by: &LineMap, params: &CompareParams) -> (f64, f64) {
    let mut walls = Walls::of(by);
    let (mut total, mut matched) = (0.0, 0.0);
    for s in &of.segments {
        for (p, len) in pieces(s, params.step) {
            total += len;
            if walls
                .nearest(&p, s.line.beta, params.max_distance, params.max_angle)
                .is_some()
            {
                matched += len;
            }
        }
    }
    (total, matched)
}

/// A map's walls with a [`WallIndex`] of them, for many nearest-wall queries.
struct Walls<'a> {
    map: &'a LineMap,
    index: WallIndex,
    /// The candidates of the last query (kept to reuse its allocation).
    candidates: Vec<usize>,
}

impl<'a> Walls<'a> {
    fn of(map: &'a LineMap) -> Self {
        Self {
            map,
            index: WallIndex::of_map(map),
            candidates: Vec::new(),
        }
    }

    /// The wall nearest to `p` among those within `max_distance` (as segments) whose
    /// direction is within `max_angle` of `beta` (either way round); of equally near
    /// walls, the first in the map.
    fn nearest(
        &mut self,
        p: &Point2<f64>,
        beta: f64,
        max_distance: f64,
        max_angle: f64,
    ) -> Option<&'a MapSegment> {
        self.index.near(p, p, max_distance, &mut self.candidates);
        let map = self.map;
        self.candidates
            .iter()
            .map(|&i| &map.segments[i])
            .filter(|s| directions_within(s.line.beta, beta, max_angle))
            .map(|s| (s, s.distance_to(p)))
            .filter(|(_, d)| *d <= max_distance)
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(s, _)| s)
    }
}

/// Whether two walls' directions `a` and `b` (rad) are within `max_angle` of each other,
/// either way round (a wall's direction and its opposite are the same wall).
fn directions_within(a: f64, b: f64, max_angle: f64) -> bool {
    let d = angle_diff(a, b).abs();
    d.min(std::f64::consts::PI - d) <= max_angle
}

/// The middles and lengths of the pieces, at most `step` long, a wall is cut into.
fn pieces(s: &MapSegment, step: f64) -> impl Iterator<Item = (Point2<f64>, f64)> + '_ {
    let length = s.length();
    let n = (length / step).ceil().max(1.0) as usize;
    (0..n).map(move |i| {
        let f = (i as f64 + 0.5) / n as f64;
        (s.start + (s.end - s.start) * f, length / n as f64)
    })
}

/// `map` with every wall moved by `pose`.
pub(crate) fn transformed(map: &LineMap, pose: &Pose2<f64>) -> LineMap {
    let segments = map
        .segments
        .iter()
        .filter_map(|s| {
            MapSegment::from_points(pose.transform_point(&s.start), pose.transform_point(&s.end))
                .ok()
        })
        .collect();
    LineMap {
        frame_id: map.frame_id.clone(),
        segments,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::{map_of, ROOM_WITH_STUB};
    use proptest::prelude::*;

    fn room() -> LineMap {
        map_of(&ROOM_WITH_STUB)
    }

    proptest! {
        /// The indexed search finds exactly the wall a search of every wall finds.
        #[test]
        fn the_indexed_search_finds_what_a_full_search_finds(
            ends in prop::collection::vec((-20.0..20.0f64, -20.0..20.0f64, -20.0..20.0f64, -20.0..20.0f64), 1..30),
            queries in prop::collection::vec((-22.0..22.0f64, -22.0..22.0f64, -3.2..3.2f64), 50),
            reach in prop_oneof![Just(0.1), Just(0.3), Just(1.0), Just(2.5)],
        ) {
            let map = LineMap {
                frame_id: "map".into(),
                segments: ends
                    .iter()
                    .filter_map(|&(a, b, c, d)| {
                        MapSegment::from_points(Point2::new(a, b), Point2::new(c, d)).ok()
                    })
                    .collect(),
            };
            let mut walls = Walls::of(&map);
            let angle = 30f64.to_radians();
            for (x, y, beta) in queries {
                let p = Point2::new(x, y);
                let full = map
                    .segments
                    .iter()
                    .filter(|s| directions_within(s.line.beta, beta, angle))
                    .map(|s| (s, s.distance_to(&p)))
                    .filter(|(_, d)| *d <= reach)
                    .min_by(|a, b| a.1.total_cmp(&b.1))
                    .map(|(s, _)| s);
                prop_assert_eq!(full, walls.nearest(&p, beta, reach, angle));
            }
        }
    }

    #[test]
    fn shares_count_matched_and_extra_length() {
        let reference = room();
        // Half the bottom wall, the right wall 5 cm off, the top wall 20 cm off (too far),
        // the left wall turned 5° (too steep), the stub missing; plus a 3 m phantom.
        let m = map_of(&[
            [0.0, 0.0, 5.0, 0.0],
            [10.05, 0.0, 10.05, 6.0],
            [10.0, 6.2, 0.0, 6.2],
            [0.0, 0.0, 6.0 * 5f64.to_radians().tan(), 6.0],
            [2.0, 3.0, 5.0, 3.0],
        ]);
        let c = compare(
            &m,
            &reference,
            &Pose2::new(0.0, 0.0, 0.0),
            &CompareParams::default(),
        );
        assert_eq!((c.reference_walls, c.map_walls), (5, 5));
        assert!((c.reference_length_m - 34.5).abs() < 1e-9, "{c:?}");
        // Matched: 5.1 m of the bottom (the half and the 0.1 m beyond its end), 6 m of
        // the right wall (the end pieces of the other walls that come within 0.1 m of it
        // have the wrong direction).
        assert!((c.matched_length_m - 11.1).abs() < 1e-9, "{c:?}");
        assert!((c.matched_share - 11.1 / 34.5).abs() < 1e-9);
        // The map's top wall, turned wall and phantom have no counterpart.
        let turned = 6.0 / 5f64.to_radians().cos();
        assert!((c.map_length_m - (5.0 + 6.0 + 10.0 + turned + 3.0)).abs() < 1e-9);
        assert!(
            (c.unmatched_map_length_m - (10.0 + turned + 3.0)).abs() < 1e-9,
            "{c:?}"
        );
    }

    #[test]
    fn alignment_undoes_a_rigid_motion() {
        let reference = room();
        let motion = Pose2::new(0.4, -0.3, 3f64.to_radians());
        let moved = transformed(&reference, &motion);
        let unaligned = compare(
            &moved,
            &reference,
            &Pose2::new(0.0, 0.0, 0.0),
            &CompareParams::default(),
        );
        assert!(unaligned.matched_share < 0.3, "{unaligned:?}");
        let found = align(&moved, &reference, &Pose2::new(0.0, 0.0, 0.0));
        let back = found.compose(&motion);
        assert!(
            back.x.abs() < 1e-6 && back.y.abs() < 1e-6 && back.theta.abs() < 1e-8,
            "{back:?}"
        );
        let aligned = compare(&moved, &reference, &found, &CompareParams::default());
        assert!(aligned.matched_share > 0.999, "{aligned:?}");
        assert!(aligned.unmatched_map_length_m < 0.05, "{aligned:?}");
    }
}
