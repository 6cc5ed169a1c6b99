//! Rays through an occupancy grid: what a laser beam would return.

use super::{OccupancyGrid, OBSTACLE_ABOVE, UNKNOWN};
use nalgebra::{Point2, Vector2};

/// Most cells of one run of obstacle cells a beam is followed through (a beam that
/// grazes along a wall would otherwise travel far inside it).
pub const MAX_RUN_CELLS: usize = 3;

/// The range a beam from `from` (grid frame) in direction `angle` (rad, grid frame) would
/// return: the middle of the first run of obstacle cells (occupancy above
/// [`OBSTACLE_ABOVE`]) it crosses, i.e. halfway between where it enters the first and
/// leaves the last of them (at most [`MAX_RUN_CELLS`]). `None` (no return) if the beam
/// first meets an unknown cell, leaves the grid, or travels farther than `max_range`.
///
/// The cells are visited in the order the beam crosses them (Amanatides and Woo 1987): from
/// the start cell, step to the neighbour across whichever cell boundary, x or y, the beam
/// reaches first, at `t = (boundary − from) / direction` along it. The middle of the run
/// is where the wall's surface most likely is: beam end points mark the cells on both sides
/// of a surface (a mapped wall is a band one to three cells thick), and a wall drawn one
/// cell thick returns the line through its cells' centres from both sides.
pub fn cast(grid: &OccupancyGrid, from: &Point2<f64>, angle: f64, max_range: f64) -> Option<f64> {
    let d = Vector2::new(angle.cos(), angle.sin());
    let res = grid.resolution;
    let (mut ix, mut iy) = grid.cell_of(from);
    // Per axis: the step between cells, the distance along the beam to the next boundary,
    // and the distance between boundaries.
    let axis = |p: f64, dp: f64, i: i64| -> (i64, f64, f64) {
        if dp > 0.0 {
            (1, ((i + 1) as f64 * res - p) / dp, res / dp)
        } else if dp < 0.0 {
            (-1, (i as f64 * res - p) / dp, -res / dp)
        } else {
            (0, f64::INFINITY, f64::INFINITY)
        }
    };
    let (step_x, mut next_x, delta_x) = axis(from.x, d.x, ix);
    let (step_y, mut next_y, delta_y) = axis(from.y, d.y, iy);
    // Distance along the beam at which it entered the current cell, and at which it
    // entered the run of obstacle cells it is in (if any) with the run's length.
    let mut entered = 0.0;
    let mut run: Option<(f64, usize)> = None;
    loop {
        let cell = grid.get(ix, iy);
        let is_obstacle = matches!(cell, Some(v) if v > OBSTACLE_ABOVE);
        let left = next_x.min(next_y);
        match run {
            Some((start, _)) if !is_obstacle => return Some(0.5 * (start + entered)),
            Some((start, n)) => run = Some((start, n + 1)),
            None if is_obstacle && entered >= max_range => return None,
            None if is_obstacle => run = Some((entered, 1)),
            None if matches!(cell, None | Some(UNKNOWN)) || left > max_range => return None,
            None => {}
        }
        if let Some((start, MAX_RUN_CELLS)) = run {
            return Some(0.5 * (start + left));
        }
        entered = left;
        if next_x < next_y {
            ix += step_x;
            next_x += delta_x;
        } else {
            iy += step_y;
            next_y += delta_y;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::{FREE, OCCUPIED};
    use super::*;
    use ekf_core::Pose2;

    /// 100 × 60 free cells of 0.1 m with an occupied column at ix = 80 (x ∈ [8.0, 8.1))
    /// and an unknown row at iy = 58.
    fn grid() -> OccupancyGrid {
        let mut g = OccupancyGrid::filled(100, 60, 0.1, Pose2::new(0.0, 0.0, 0.0), FREE);
        for iy in 0..60 {
            g.set(80, iy, OCCUPIED);
        }
        for ix in 0..100 {
            g.set(ix, 58, UNKNOWN);
        }
        g
    }

    #[test]
    fn a_beam_returns_the_distance_to_the_wall_cells_centre_line() {
        let g = grid();
        let from = Point2::new(1.0, 1.05);
        // Straight at the wall: its centre line is x = 8.05.
        let r = cast(&g, &from, 0.0, 20.0).unwrap();
        assert!((r - 7.05).abs() < 1e-12, "{r}");
        // At 30°: the hit cell's centre projected onto the beam is within half a cell
        // (along x) of where the beam crosses x = 8.05.
        let a = 30f64.to_radians();
        let r = cast(&g, &from, a, 20.0).unwrap();
        let exact = 7.05 / a.cos();
        assert!((r - exact).abs() < 0.05 / a.cos() + 0.05, "{r} vs {exact}");
        // Beyond the range, into unknown cells, out of the grid: no return.
        assert_eq!(cast(&g, &from, 0.0, 6.9), None);
        assert_eq!(cast(&g, &from, std::f64::consts::FRAC_PI_2, 20.0), None);
        assert_eq!(cast(&g, &from, std::f64::consts::PI, 20.0), None);
    }

    #[test]
    fn both_sides_of_a_thin_wall_see_the_same_line() {
        let g = grid();
        let left = cast(&g, &Point2::new(5.05, 1.0), 0.0, 20.0).unwrap();
        let right = cast(&g, &Point2::new(9.05, 1.0), std::f64::consts::PI, 20.0).unwrap();
        assert!((5.05 + left - 8.05).abs() < 1e-12);
        assert!((9.05 - right - 8.05).abs() < 1e-12);
    }

    #[test]
    fn a_band_two_cells_thick_returns_its_middle_and_a_grazing_beam_stops_in_it() {
        let mut g = grid();
        for iy in 0..58 {
            g.set(81, iy, OCCUPIED);
        }
        // Perpendicular: halfway through the band, at its inner boundary x = 8.1.
        let r = cast(&g, &Point2::new(1.0, 1.05), 0.0, 20.0).unwrap();
        assert!((r - 7.1).abs() < 1e-12, "{r}");
        // Along the band, from inside its first cell: the run is cut after three cells.
        let r = cast(
            &g,
            &Point2::new(8.05, 1.0),
            std::f64::consts::FRAC_PI_2,
            20.0,
        )
        .unwrap();
        assert!((r - 0.5 * (0.0 + 0.3)).abs() < 1e-12, "{r}");
    }

    #[test]
    fn diagonal_beams_do_not_slip_between_the_cells_of_a_diagonal_wall() {
        // A wall along the diagonal drawn as a 4-connected staircase (as `from_lines`
        // draws walls) stops every beam that reaches it.
        let mut g = OccupancyGrid::filled(50, 50, 0.1, Pose2::new(0.0, 0.0, 0.0), FREE);
        for i in 0..50 {
            g.set(i, i, OCCUPIED);
            g.set(i + 1, i, OCCUPIED);
        }
        let from = Point2::new(4.05, 1.05);
        for k in 0..360 {
            let a = f64::from(k).to_radians();
            match cast(&g, &from, a, 20.0) {
                Some(r) => {
                    let hit = from + Vector2::new(a.cos(), a.sin()) * r;
                    assert!(hit.y <= hit.x + 0.2, "beam {k}° went through: {hit:?}");
                }
                // Only beams that leave the grid before reaching the wall find none.
                None => {
                    let d = Vector2::new(a.cos(), a.sin());
                    let s = (from.x - from.y) / (d.y - d.x);
                    let meets = from + d * s;
                    let inside = |v: f64| (0.3..4.7).contains(&v);
                    assert!(
                        !(s > 0.0 && inside(meets.x) && inside(meets.y)),
                        "beam {k}° found no wall"
                    );
                }
            }
        }
    }
}
