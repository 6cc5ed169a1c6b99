//! Helpers shared by the unit tests of several modules.

use lrf_lines::{LineMap, MapSegment};
use nalgebra::Point2;

/// A line map of walls given as `[x0, y0, x1, y1]` (m).
pub fn map_of(walls: &[[f64; 4]]) -> LineMap {
    LineMap::new(
        walls
            .iter()
            .map(|&[x0, y0, x1, y1]| {
                MapSegment::from_points(Point2::new(x0, y0), Point2::new(x1, y1)).unwrap()
            })
            .collect(),
    )
}

/// A 10 × 6 m room with a 2.5 m stub wall inside.
pub const ROOM_WITH_STUB: [[f64; 4]; 5] = [
    [0.0, 0.0, 10.0, 0.0],
    [10.0, 0.0, 10.0, 6.0],
    [10.0, 6.0, 0.0, 6.0],
    [0.0, 6.0, 0.0, 0.0],
    [4.0, 0.0, 4.0, 2.5],
];
