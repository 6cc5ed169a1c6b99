//! A correlative search of a scan's points over a window of poses, for a loop closure
//! where the relocalization search finds no pair of walls (docs/maps.md, "Building a map
//! without a reference"): open halls and cluttered rooms show too few long lines, but
//! their points still say where the robot is.
//!
//! The reference points are rasterised into a grid of cells of the matcher's
//! `max_distance` `d`, each cell marked if a reference point lies in it or a neighbour
//! (a hit within about `2d`). Every heading of the window (steps of [`ANGLE_STEP`]) and
//! every position on the grid's lattice within the radius is scored by how many of the
//! scan's points land on marked cells, as Olson's correlative scan matcher does at its
//! coarse level. The best few distinct poses are then aligned by the point-to-line
//! matcher ([`align`]); the best alignment stands if it matches at least
//! [`PointSearch::min_share`] of the points and no distinct alignment comes within
//! [`PointSearch::min_margin`] of it — a corridor, which looks the same all along, gives
//! nothing.

use super::scan_match::{align, cell_of, MatchParams, ReferenceCloud, ScanPoints};
use ekf_core::{angle_diff, wrap_angle, Pose2};
use nalgebra::{Matrix2, Vector2};

/// Heading step of the search (rad): a point 10 m away moves by 0.35 m, within the
/// coarse grid's reach of 0.3–0.6 m.
const ANGLE_STEP: f64 = 2.0 * std::f64::consts::PI / 180.0;
/// Points of the scan scored at the coarse level, spread evenly over it.
const SCORED_POINTS: usize = 100;
/// Coarse poses aligned by the matcher.
const ALIGNED_CANDIDATES: usize = 8;

/// Where and how the search looks.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointSearch {
    /// The pose the window is centred on.
    pub center: Pose2<f64>,
    /// Positions within this distance (m) of the centre's ...
    pub radius: f64,
    /// ... and headings within this (rad) of its.
    pub max_turn: f64,
    /// Share of the scan's points the best alignment must match.
    pub min_share: f64,
    /// The best alignment must match at least this multiple of any distinct one's points.
    pub min_margin: f64,
    /// Alignments this far apart (m) ...
    pub distinct_distance: f64,
    /// ... or turned this much (rad) are distinct.
    pub distinct_angle: f64,
}

/// The marked cells of the reference's points, dilated by one cell.
struct HitGrid {
    origin: (i64, i64),
    width: usize,
    height: usize,
    hits: Vec<bool>,
}

impl HitGrid {
    fn new(reference: &ReferenceCloud, cell: f64) -> Option<Self> {
        let keys: Vec<(i64, i64)> = reference.points().map(|q| cell_of(q, cell)).collect();
        let x0 = keys.iter().map(|k| k.0).min()? - 1;
        let y0 = keys.iter().map(|k| k.1).min()? - 1;
        let width = (keys.iter().map(|k| k.0).max()? - x0 + 2) as usize;
        let height = (keys.iter().map(|k| k.1).max()? - y0 + 2) as usize;
        let mut hits = vec![false; width * height];
        for (kx, ky) in keys {
            for dx in -1..=1 {
                for dy in -1..=1 {
                    let (ix, iy) = ((kx - x0 + dx) as usize, (ky - y0 + dy) as usize);
                    hits[iy * width + ix] = true;
                }
            }
        }
        Some(Self {
            origin: (x0, y0),
            width,
            height,
            hits,
        })
    }

    fn hit(&self, kx: i64, ky: i64) -> bool {
        let (ix, iy) = (kx - self.origin.0, ky - self.origin.1);
        ix >= 0
            && iy >= 0
            && (ix as usize) < self.width
            && (iy as usize) < self.height
            && self.hits[iy as usize * self.width + ix as usize]
    }
}

/// The pose within `window` that puts `scan` (robot frame) on `reference` (see the module
/// documentation), or `None` if none stands or it is ambiguous.
pub fn search(
    reference: &ReferenceCloud,
    scan: &ScanPoints,
    window: &PointSearch,
    matcher: &MatchParams,
) -> Option<Pose2<f64>> {
    let cell = matcher.max_distance;
    let grid = HitGrid::new(reference, cell)?;
    let points: Vec<Vector2<f64>> = {
        let all = scan.points();
        let stride = all.len().div_ceil(SCORED_POINTS).max(1);
        all.iter().step_by(stride).copied().collect()
    };
    if points.is_empty() {
        return None;
    }
    let reach = (window.radius / cell).ceil() as i64;
    let turns = (window.max_turn / ANGLE_STEP).floor() as i64;
    // (score, cell shift x, y, heading step)
    let mut coarse: Vec<(usize, i64, i64, i64)> = Vec::new();
    let mut keys = Vec::with_capacity(points.len());
    for a in -turns..=turns {
        let theta = window.center.theta + a as f64 * ANGLE_STEP;
        let (s, c) = theta.sin_cos();
        let rotation = Matrix2::new(c, -s, s, c);
        keys.clear();
        keys.extend(points.iter().map(|p| {
            cell_of(
                &(rotation * p + Vector2::new(window.center.x, window.center.y)),
                cell,
            )
        }));
        for i in -reach..=reach {
            for j in -reach..=reach {
                if ((i * i + j * j) as f64).sqrt() * cell > window.radius + cell {
                    continue;
                }
                let score = keys.iter().filter(|k| grid.hit(k.0 + i, k.1 + j)).count();
                coarse.push((score, i, j, a));
            }
        }
    }
    coarse.sort_by_key(|c| std::cmp::Reverse(c.0));
    // The best coarse poses, one per neighbourhood of the lattice.
    let mut starts: Vec<(i64, i64, i64)> = Vec::new();
    for &(_, i, j, a) in &coarse {
        if starts.len() == ALIGNED_CANDIDATES {
            break;
        }
        if starts
            .iter()
            .all(|s| (s.0 - i).abs() > 1 || (s.1 - j).abs() > 1 || (s.2 - a).abs() > 2)
        {
            starts.push((i, j, a));
        }
    }
    let mut aligned: Vec<(usize, Pose2<f64>)> = starts
        .iter()
        .filter_map(|&(i, j, a)| {
            let start = Pose2::new(
                window.center.x + i as f64 * cell,
                window.center.y + j as f64 * cell,
                wrap_angle(window.center.theta + a as f64 * ANGLE_STEP),
            );
            align(reference, scan, start, matcher).map(|r| (r.matched, r.pose))
        })
        .collect();
    aligned.sort_by_key(|a| std::cmp::Reverse(a.0));
    let &(best_matched, best) = aligned.first()?;
    if (best_matched as f64) < window.min_share * scan.len() as f64 {
        return None;
    }
    let distinct = |p: &Pose2<f64>| {
        (p.x - best.x).hypot(p.y - best.y) > window.distinct_distance
            || angle_diff(p.theta, best.theta).abs() > window.distinct_angle
    };
    let runner_up = aligned
        .iter()
        .filter(|(_, p)| distinct(p))
        .map(|&(m, _)| m)
        .max()
        .unwrap_or(0);
    (best_matched as f64 >= window.min_margin * runner_up as f64).then_some(best)
}

#[cfg(test)]
mod tests {
    use super::super::scan_match::tests::{reference, seen_from, walls, ROOM};
    use super::*;

    fn window(center: Pose2<f64>) -> PointSearch {
        PointSearch {
            center,
            radius: 2.0,
            max_turn: 20f64.to_radians(),
            min_share: 0.6,
            min_margin: 1.2,
            distinct_distance: 0.5,
            distinct_angle: 10f64.to_radians(),
        }
    }

    #[test]
    fn a_room_is_found_from_a_guess_over_a_metre_and_ten_degrees_off() {
        let room = walls(&ROOM);
        let scan = seen_from(&room, &Pose2::new(2.5, 2.0, 0.0));
        let guess = Pose2::new(3.4, 1.2, 10f64.to_radians());
        let found = search(
            &reference(&room),
            &scan,
            &window(guess),
            &MatchParams::default(),
        )
        .unwrap();
        assert!(
            (found.x - 2.5).abs() < 1e-3 && (found.y - 2.0).abs() < 1e-3,
            "{found:?}"
        );
        assert!(found.theta.abs() < 1e-4, "{found:?}");
    }

    #[test]
    fn a_corridor_that_looks_the_same_all_along_gives_nothing() {
        // Two parallel walls and nothing else: every shift along them fits as well.
        let corridor = walls(&[((-50.0, 1.0), (50.0, 1.0)), ((50.0, -1.0), (-50.0, -1.0))]);
        let seen = walls(&[((-8.0, 1.0), (8.0, 1.0)), ((8.0, -1.0), (-8.0, -1.0))]);
        let scan = seen_from(&seen, &Pose2::new(0.0, 0.0, 0.0));
        let params = MatchParams::default();
        let found = search(
            &reference(&corridor),
            &scan,
            &window(Pose2::new(0.3, 0.2, 0.05)),
            &params,
        );
        assert_eq!(found, None);
    }

    #[test]
    fn nothing_is_found_where_the_reference_is_not() {
        let room = walls(&ROOM);
        let scan = seen_from(&room, &Pose2::new(2.5, 2.0, 0.0));
        let far = Pose2::new(30.0, 30.0, 0.0);
        let params = MatchParams::default();
        assert_eq!(
            search(&reference(&room), &scan, &window(far), &params),
            None
        );
    }
}
