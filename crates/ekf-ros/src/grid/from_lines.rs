//! Drawing a line map into an occupancy grid, for ROS tools that need one (Nav2's
//! `map_server`, AMCL, costmaps).

use super::{OccupancyGrid, FREE, OCCUPIED};
use ekf_core::Pose2;
use lrf_lines::LineMap;
use nalgebra::{Point2, Vector2};

/// The most cells a drawn grid may have (400 M: 20 km² at 5 cm); a larger one is refused
/// rather than filling the memory.
pub const MAX_CELLS: usize = 400_000_000;

/// Why a line map could not be drawn.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DrawError {
    /// The resolution or margin is not a positive (resp. non-negative) finite length.
    #[error("{name} must be a finite length > 0 m (≥ 0 for the margin), not {value}")]
    BadParameter {
        /// `resolution` or `margin`.
        name: &'static str,
        /// The value given.
        value: f64,
    },
    /// The map has no walls.
    #[error("the map has no walls to draw")]
    Empty,
    /// The grid would have more than [`MAX_CELLS`] cells.
    #[error("a {width} × {height} grid is more than {MAX_CELLS} cells; use a coarser resolution")]
    TooLarge {
        /// Cells per row.
        width: u64,
        /// Rows.
        height: u64,
    },
}

/// The grid of `map`'s walls: cells of side `resolution` covering the walls' bounding box
/// grown by `margin` on each side (axis-aligned, origin at its lower-left corner), every
/// cell a wall passes through occupied and the others free — a line map says where walls
/// are, not what was seen, so nothing is unknown.
///
/// A wall marks the cells of points every quarter cell along it, and of the points a
/// quarter cell to either side of those: a band one cell wide where the wall runs through
/// the middle of its cells and two where it runs near their boundary, so that the middle
/// of the band, where [`super::raycast::cast`] puts a beam's return, is within a quarter
/// cell of the wall (not half a cell, as with the cells it passes through alone). The band
/// is connected, and a ray cannot slip through it.
pub fn draw(map: &LineMap, resolution: f64, margin: f64) -> Result<OccupancyGrid, DrawError> {
    if !(resolution.is_finite() && resolution > 0.0) {
        return Err(DrawError::BadParameter {
            name: "resolution",
            value: resolution,
        });
    }
    if !(margin.is_finite() && margin >= 0.0) {
        return Err(DrawError::BadParameter {
            name: "margin",
            value: margin,
        });
    }
    let points = || map.segments.iter().flat_map(|s| [s.start, s.end]);
    let (mut lo, mut hi) = (
        Point2::new(f64::INFINITY, f64::INFINITY),
        Point2::new(f64::NEG_INFINITY, f64::NEG_INFINITY),
    );
    for p in points() {
        lo = lo.inf(&p);
        hi = hi.sup(&p);
    }
    if map.is_empty() {
        return Err(DrawError::Empty);
    }
    let cells_along = |extent: f64| ((extent + 2.0 * margin) / resolution).ceil().max(1.0);
    let (w, h) = (cells_along(hi.x - lo.x), cells_along(hi.y - lo.y));
    if w * h > MAX_CELLS as f64 {
        return Err(DrawError::TooLarge {
            width: w as u64,
            height: h as u64,
        });
    }
    let origin = Pose2::new(lo.x - margin, lo.y - margin, 0.0);
    let mut grid = OccupancyGrid::filled(w as usize, h as usize, resolution, origin, FREE);
    for s in &map.segments {
        let (a, b) = (grid.to_grid_frame(&s.start), grid.to_grid_frame(&s.end));
        let steps = ((b - a).norm() / (0.25 * resolution)).ceil() as usize;
        let along = (b - a).normalize();
        let side = Vector2::new(-along.y, along.x) * (0.25 * resolution);
        for i in 0..=steps {
            let p = a + (b - a) * (i as f64 / steps.max(1) as f64);
            for q in [p - side, p, p + side] {
                let (ix, iy) = grid.cell_of(&q);
                grid.set(ix, iy, OCCUPIED);
            }
        }
    }
    Ok(grid)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::map_of;

    #[test]
    fn walls_occupy_a_band_of_cells_centred_on_them() {
        let m = map_of(&[
            [0.0, 0.0, 2.0, 0.0],
            [2.0, 0.0, 2.0, 1.0],
            [0.0, 1.05, 1.0, 1.05],
        ]);
        let g = draw(&m, 0.1, 0.5).unwrap();
        assert_eq!((g.width, g.height), (30, 21));
        assert_eq!(g.origin, Pose2::new(-0.5, -0.5, 0.0));
        let occupied: Vec<(i64, i64)> = (0..21)
            .flat_map(|iy| (0..30).map(move |ix| (ix, iy)))
            .filter(|&(ix, iy)| g.get(ix, iy) == Some(OCCUPIED))
            .collect();
        // In the grid's frame the bottom wall runs along the boundary y = 0.5 between
        // rows 4 and 5: it marks both, columns 5..=25. The right wall runs along x = 2.5,
        // rows 5..=15: columns 24 and 25. The top wall runs through the middle of row 15:
        // only that row, columns 5..=15.
        let mut want: Vec<(i64, i64)> = (5..=25).flat_map(|ix| [(ix, 4), (ix, 5)]).collect();
        want.extend((6..=15).flat_map(|iy| [(24, iy), (25, iy)]));
        want.extend((5..=15).map(|ix| (ix, 15)));
        want.sort_by_key(|&(ix, iy)| (iy, ix));
        want.dedup();
        assert_eq!(occupied, want);
        assert_eq!(g.counts(), (630 - want.len(), want.len(), 0));
    }

    #[test]
    fn bad_requests_are_refused() {
        let m = map_of(&[[0.0, 0.0, 1.0, 0.0]]);
        assert!(matches!(
            draw(&m, 0.0, 1.0),
            Err(DrawError::BadParameter {
                name: "resolution",
                ..
            })
        ));
        assert!(matches!(
            draw(&m, 0.05, f64::NAN),
            Err(DrawError::BadParameter { name: "margin", .. })
        ));
        assert_eq!(draw(&LineMap::default(), 0.05, 1.0), Err(DrawError::Empty));
        let huge = map_of(&[[0.0, 0.0, 1e6, 1e6]]);
        assert!(matches!(
            draw(&huge, 0.05, 1.0),
            Err(DrawError::TooLarge { .. })
        ));
    }
}
