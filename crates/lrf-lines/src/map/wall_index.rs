//! A spatial index of wall segments, so that [`super::MapBuilder`] compares a sighting
//! only with the walls near it instead of with every wall so far (which made building a
//! map from a long log quadratic in its length), and a map comparison looks for a
//! point's nearest wall among the walls near it.

use alloc::collections::BTreeMap;
use alloc::vec::Vec;
use nalgebra::Point2;

/// Side of a cell of the index (m). Walls are a few metres to tens of metres long and a
/// sighting is compared with the walls within about a metre of it, so a few metres keeps
/// both the cells per wall and the walls per cell small.
const CELL_M: f64 = 4.0;

/// Spacing of the points sampled along a segment to find the cells it passes through (m):
/// half a cell, so every point of the segment is within a quarter cell of a sample.
const SAMPLE_STEP_M: f64 = CELL_M / 2.0;

/// Segments longer than this are not rasterised but kept in a list that every query
/// returns: no real wall is this long, and a finite but absurd one must not make the index
/// walk billions of cells.
const MAX_INDEXED_LENGTH_M: f64 = 10_000.0;

/// Wall ids by the square cells (`CELL_M` = 4 m a side) their segments pass through.
///
/// [`near`](Self::near) returns every id whose segment (as last inserted) comes within
/// `reach` of the query segment, and possibly a few more: callers test the candidates
/// exactly. A segment is registered in the cells of points sampled every
/// `SAMPLE_STEP_M` = 2 m along it; a query looks in the cells of its own samples dilated
/// by `k = ⌈(reach + SAMPLE_STEP_M) / CELL_M⌉` cells, which covers any pair of points
/// within `reach` of each other (each is within `SAMPLE_STEP_M / 2` of a sample).
/// Segments longer than 10 km are not rasterised: every query returns them.
#[derive(Debug, Clone, Default)]
pub struct WallIndex {
    cells: BTreeMap<(i32, i32), Vec<usize>>,
    oversize: Vec<usize>,
}

impl WallIndex {
    /// The walls of `map`, each registered under its position in `map.segments`.
    pub fn of_map(map: &super::LineMap) -> Self {
        let mut index = Self::default();
        for (id, wall) in map.segments.iter().enumerate() {
            index.insert(id, &wall.start, &wall.end);
        }
        index
    }

    /// Registers `id` in the cells `start`–`end` passes through. Inserting the same id
    /// again (after its wall grew or moved) adds the new cells; old cells keep it, which
    /// only costs a candidate that fails the exact test.
    pub fn insert(&mut self, id: usize, start: &Point2<f64>, end: &Point2<f64>) {
        if !fits(start, end) {
            if !self.oversize.contains(&id) {
                self.oversize.push(id);
            }
            return;
        }
        for cell in sampled_cells(start, end) {
            let ids = self.cells.entry(cell).or_default();
            if !ids.contains(&id) {
                ids.push(id);
            }
        }
    }

    /// Clears `out` and fills it with the ids, ascending and each once, of the segments
    /// that may come within `reach` (m) of `start`–`end`.
    pub fn near(&self, start: &Point2<f64>, end: &Point2<f64>, reach: f64, out: &mut Vec<usize>) {
        out.clear();
        out.extend_from_slice(&self.oversize);
        if !fits(start, end) {
            out.extend(self.cells.values().flatten().copied());
        } else {
            let k = libm::ceil((reach + SAMPLE_STEP_M) / CELL_M) as i32;
            for (cx, cy) in sampled_cells(start, end) {
                for x in cx.saturating_sub(k)..=cx.saturating_add(k) {
                    let column = self
                        .cells
                        .range((x, cy.saturating_sub(k))..=(x, cy.saturating_add(k)));
                    out.extend(column.flat_map(|(_, ids)| ids.iter().copied()));
                }
            }
        }
        out.sort_unstable();
        out.dedup();
    }
}

/// `true` if the segment is short enough to rasterise.
fn fits(start: &Point2<f64>, end: &Point2<f64>) -> bool {
    (end - start).norm() <= MAX_INDEXED_LENGTH_M
}

/// The cells of points every [`SAMPLE_STEP_M`] from `start` to `end` (both included);
/// consecutive repeats are left out.
fn sampled_cells(start: &Point2<f64>, end: &Point2<f64>) -> impl Iterator<Item = (i32, i32)> {
    let (start, delta) = (*start, end - start);
    let steps = libm::ceil(delta.norm() / SAMPLE_STEP_M) as usize;
    let mut last = None;
    (0..=steps).filter_map(move |i| {
        let f = if steps == 0 {
            0.0
        } else {
            i as f64 / steps as f64
        };
        let p = start + delta * f;
        // `as` saturates: coordinates beyond ±8.6e6 km share the outermost cells.
        let cell = (
            libm::floor(p.x / CELL_M) as i32,
            libm::floor(p.y / CELL_M) as i32,
        );
        (last.replace(cell) != Some(cell)).then_some(cell)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Distance between two segments (exact, by end points to segments; they are taken
    /// as not crossing, which the test cases ensure or do not rely on).
    fn segment_distance(a: (Point2<f64>, Point2<f64>), b: (Point2<f64>, Point2<f64>)) -> f64 {
        let point_to = |p: Point2<f64>, (s, e): (Point2<f64>, Point2<f64>)| {
            let d = e - s;
            let t = ((p - s).dot(&d) / d.norm_squared()).clamp(0.0, 1.0);
            (s + d * t - p).norm()
        };
        point_to(a.0, b)
            .min(point_to(a.1, b))
            .min(point_to(b.0, a))
            .min(point_to(b.1, a))
    }

    #[test]
    fn every_segment_within_reach_is_a_candidate() {
        // A deterministic spread of segments of 0.1–30 m in a 200 m square, queried by
        // others: every one within reach must be returned (extra ones are allowed).
        let mut seed = 0x9e37_79b9_7f4a_7c15_u64;
        let mut next = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut segment = || {
            let s = Point2::new(200.0 * next() - 100.0, 200.0 * next() - 100.0);
            let (len, dir) = (0.1 + 30.0 * next(), 6.3 * next());
            (s, s + nalgebra::Vector2::new(dir.cos(), dir.sin()) * len)
        };
        let walls: Vec<_> = (0..400).map(|_| segment()).collect();
        let mut index = WallIndex::default();
        for (id, (s, e)) in walls.iter().enumerate() {
            index.insert(id, s, e);
        }
        let mut out = Vec::new();
        let mut checked = 0;
        for _ in 0..400 {
            let q = segment();
            let reach = 1.3;
            index.near(&q.0, &q.1, reach, &mut out);
            assert!(out.windows(2).all(|w| w[0] < w[1]), "ascending, no repeats");
            for (id, w) in walls.iter().enumerate() {
                if segment_distance(*w, q) <= reach {
                    checked += 1;
                    assert!(out.contains(&id), "wall {id} {w:?} near {q:?} missed");
                }
            }
        }
        assert!(
            checked > 100,
            "the test must exercise near pairs: {checked}"
        );
    }

    #[test]
    fn far_walls_are_not_candidates_and_oversize_ones_always_are() {
        let p = Point2::new;
        let mut index = WallIndex::default();
        index.insert(0, &p(0.0, 0.0), &p(10.0, 0.0));
        index.insert(1, &p(100.0, 100.0), &p(110.0, 100.0));
        index.insert(2, &p(-1e9, 5.0), &p(1e9, 5.0));
        let mut out = Vec::new();
        index.near(&p(2.0, 0.5), &p(8.0, 0.5), 1.0, &mut out);
        assert_eq!(out, [0, 2]);
        index.near(&p(105.0, 101.0), &p(106.0, 101.0), 1.0, &mut out);
        assert_eq!(out, [1, 2]);
        // A query too long to rasterise gets every wall.
        index.near(&p(-1e9, 0.0), &p(1e9, 0.0), 1.0, &mut out);
        assert_eq!(out, [0, 1, 2]);
    }
}
