//! A grid over a line map's walls, for "which wall is nearest this point, within `reach`"
//! asked many times (map comparison, its alignment): each query looks only at the walls
//! registered in the point's cell instead of at every wall of the map.
//!
//! A wall is registered in every cell a point within `reach` of it can fall in: it is
//! sampled every `cell` metres, and each sample registers the cells that overlap the
//! square of half-side `reach + cell / 2` around it. A point `p` within `reach` of the
//! wall is within `reach` of the wall's point `s` nearest to it, and `s` is within
//! `cell / 2` of a sample `q`, so `|p − q|∞ ≤ reach + cell / 2`: `p`'s cell is registered.
//! The work and memory grow with the walls' length, not with the map's area. A wall
//! longer than [`MAX_SAMPLES`] cells (a stray wall of a damaged map) is not registered;
//! every query looks at it instead.

use lrf_lines::{LineMap, MapSegment};
use nalgebra::Point2;
use std::collections::HashMap;

/// Walls longer than this many cells are not registered (see the module documentation):
/// 25 km at the smallest cell, far beyond a building's walls.
pub const MAX_SAMPLES: usize = 100_000;

/// The walls of one map by grid cell (see the module documentation).
#[derive(Debug, Clone)]
pub struct WallIndex<'a> {
    map: &'a LineMap,
    reach: f64,
    cell: f64,
    cells: HashMap<(i64, i64), Vec<usize>>,
    /// Walls too long to register, looked at by every query.
    unregistered: Vec<usize>,
}

impl<'a> WallIndex<'a> {
    /// The index of `map` for queries within `reach` (m, > 0). The cell is `reach`, but
    /// at least 0.25 m: smaller cells would register each wall in many more of them.
    pub fn new(map: &'a LineMap, reach: f64) -> Self {
        let cell = reach.max(0.25);
        let mut cells: HashMap<(i64, i64), Vec<usize>> = HashMap::new();
        let mut unregistered = Vec::new();
        let half = reach + 0.5 * cell;
        for (i, wall) in map.segments.iter().enumerate() {
            let samples = (wall.length() / cell).ceil().max(1.0);
            // Also a non-finite length or cell.
            if !samples.is_finite() || samples > MAX_SAMPLES as f64 {
                unregistered.push(i);
                continue;
            }
            let samples = samples as usize;
            for k in 0..=samples {
                let q = wall.start + (wall.end - wall.start) * (k as f64 / samples as f64);
                let (x0, y0) = cell_of(q.x - half, q.y - half, cell);
                let (x1, y1) = cell_of(q.x + half, q.y + half, cell);
                for cx in x0..=x1 {
                    for cy in y0..=y1 {
                        let list = cells.entry((cx, cy)).or_default();
                        // Walls are registered in order: a repeat is the last entry.
                        if list.last() != Some(&i) {
                            list.push(i);
                        }
                    }
                }
            }
        }
        Self {
            map,
            reach,
            cell,
            cells,
            unregistered,
        }
    }

    /// The wall nearest to `p` (as a segment) among those within `max_distance` of it
    /// (at most the index's `reach`) that `accept` keeps.
    pub fn nearest(
        &self,
        p: &Point2<f64>,
        max_distance: f64,
        accept: impl Fn(&MapSegment) -> bool,
    ) -> Option<&'a MapSegment> {
        let max_distance = max_distance.min(self.reach);
        let map = self.map;
        let registered = self
            .cells
            .get(&cell_of(p.x, p.y, self.cell))
            .map_or(&[][..], Vec::as_slice);
        registered
            .iter()
            .chain(&self.unregistered)
            .map(|&i| &map.segments[i])
            .filter(|s| accept(s))
            .map(|s| (s, s.distance_to(p)))
            .filter(|(_, d)| *d <= max_distance)
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(s, _)| s)
    }
}

/// The cell of `(x, y)`; far-off or non-finite coordinates saturate (and find nothing).
fn cell_of(x: f64, y: f64, cell: f64) -> (i64, i64) {
    ((x / cell).floor() as i64, (y / cell).floor() as i64)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn wall(x0: f64, y0: f64, x1: f64, y1: f64) -> MapSegment {
        MapSegment::from_points(Point2::new(x0, y0), Point2::new(x1, y1)).unwrap()
    }

    proptest! {
        /// The index finds exactly what a search of every wall finds.
        #[test]
        fn the_index_finds_what_a_full_search_finds(
            ends in prop::collection::vec((-20.0..20.0f64, -20.0..20.0f64, -20.0..20.0f64, -20.0..20.0f64), 1..30),
            queries in prop::collection::vec((-22.0..22.0f64, -22.0..22.0f64), 50),
            reach in prop_oneof![Just(0.1), Just(0.3), Just(1.0), Just(2.5)],
        ) {
            let map = LineMap {
                frame_id: "map".into(),
                segments: ends
                    .iter()
                    .filter_map(|&(a, b, c, d)| MapSegment::from_points(Point2::new(a, b), Point2::new(c, d)).ok())
                    .collect(),
            };
            let index = WallIndex::new(&map, reach);
            for (x, y) in queries {
                let p = Point2::new(x, y);
                let full = map
                    .segments
                    .iter()
                    .map(|s| (s, s.distance_to(&p)))
                    .filter(|(_, d)| *d <= reach)
                    .min_by(|a, b| a.1.total_cmp(&b.1))
                    .map(|(s, _)| s.distance_to(&p));
                let indexed = index.nearest(&p, reach, |_| true).map(|s| s.distance_to(&p));
                prop_assert_eq!(full, indexed);
            }
        }
    }

    #[test]
    fn a_wall_too_long_to_register_is_still_found() {
        let map = LineMap {
            frame_id: "map".into(),
            segments: vec![wall(0.0, 0.0, 1e7, 0.0), wall(0.0, 1.0, 10.0, 1.0)],
        };
        let index = WallIndex::new(&map, 0.1);
        assert_eq!(index.unregistered, vec![0]);
        let far = index
            .nearest(&Point2::new(5e6, 0.05), 0.1, |_| true)
            .unwrap();
        assert_eq!(far.end, Point2::new(1e7, 0.0));
        let near = index
            .nearest(&Point2::new(5.0, 0.95), 0.1, |_| true)
            .unwrap();
        assert_eq!(near.start, Point2::new(0.0, 1.0));
    }

    #[test]
    fn a_query_keeps_only_the_walls_it_accepts_and_within_its_distance() {
        let map = LineMap {
            frame_id: "map".into(),
            segments: vec![wall(0.0, 0.0, 10.0, 0.0), wall(0.0, 0.5, 10.0, 0.5)],
        };
        let index = WallIndex::new(&map, 1.0);
        let p = Point2::new(5.0, 0.2);
        let nearest = index.nearest(&p, 1.0, |_| true).unwrap();
        assert_eq!(nearest.start, Point2::new(0.0, 0.0));
        let upper = index.nearest(&p, 1.0, |s| s.start.y > 0.1).unwrap();
        assert_eq!(upper.start, Point2::new(0.0, 0.5));
        assert!(index.nearest(&p, 0.1, |_| true).is_none());
        assert!(index
            .nearest(&Point2::new(5.0, 3.0), 1.0, |_| true)
            .is_none());
    }
}
