//! Rooms as sets of wall segments, the built-in ones of the experiments, and ray casting.

use ekf_core::Pose2;
use lrf_lines::{LineMap, MapSegment};
use nalgebra::{Point2, Vector2};

/// A room: the walls a simulated laser sees, as segments in the world frame (m).
#[derive(Debug, Clone, PartialEq)]
pub struct Room {
    /// The walls.
    pub walls: Vec<MapSegment>,
}

/// An axis-aligned box `(min, max)` (m).
pub type Bounds = (Point2<f64>, Point2<f64>);

impl Room {
    /// A room whose walls join the `corners` in order, closing the polygon, plus square
    /// pillars of side `pillar_side` centred at `pillars`.
    pub fn polygon(corners: &[[f64; 2]], pillars: &[[f64; 2]], pillar_side: f64) -> Self {
        let mut walls = Vec::new();
        let mut add_loop = |pts: &[Point2<f64>]| {
            for (i, a) in pts.iter().enumerate() {
                let b = pts[(i + 1) % pts.len()];
                // The built-in corners are distinct, so every segment is valid.
                if let Ok(s) = MapSegment::from_points(*a, b) {
                    walls.push(s);
                }
            }
        };
        let corners: Vec<_> = corners.iter().map(|c| Point2::new(c[0], c[1])).collect();
        add_loop(&corners);
        let h = pillar_side / 2.0;
        for c in pillars {
            add_loop(&[
                Point2::new(c[0] - h, c[1] - h),
                Point2::new(c[0] + h, c[1] - h),
                Point2::new(c[0] + h, c[1] + h),
                Point2::new(c[0] - h, c[1] + h),
            ]);
        }
        Self { walls }
    }

    /// The paper's test room (§IV): a rectangular flat-wall enclosure, 6 m × 4 m, with
    /// its corner at the origin.
    pub fn paper() -> Self {
        Self::polygon(&[[0.0, 0.0], [6.0, 0.0], [6.0, 4.0], [0.0, 4.0]], &[], 0.0)
    }

    /// An L-shaped room, 10 m × 8 m with a 5 m × 4 m corner cut out, and three square
    /// pillars (0.4 m) that occlude parts of the walls.
    pub fn l_shaped() -> Self {
        Self::polygon(
            &[
                [0.0, 0.0],
                [10.0, 0.0],
                [10.0, 4.0],
                [5.0, 4.0],
                [5.0, 8.0],
                [0.0, 8.0],
            ],
            &[[2.5, 2.0], [7.5, 2.0], [2.5, 6.0]],
            0.4,
        )
    }

    /// A corridor 20 m long and 2.2 m wide, closed at both ends: along most of it only
    /// the two parallel walls are in range, so the position along it is unobservable
    /// from the laser there.
    pub fn corridor() -> Self {
        Self::polygon(
            &[[0.0, 0.0], [20.0, 0.0], [20.0, 2.2], [0.0, 2.2]],
            &[],
            0.0,
        )
    }

    /// Two rooms joined by a corridor: room A 6 m × 4 m at the origin, a corridor 8 m
    /// long and 2 m wide from the middle of its east wall, room B 6 m × 4 m beyond. From
    /// room A the laser (8 m) does not see room B: a first-scan map covers room A only.
    pub fn two_rooms() -> Self {
        Self::polygon(
            &[
                [0.0, 0.0],
                [6.0, 0.0],
                [6.0, 1.0],
                [14.0, 1.0],
                [14.0, 0.0],
                [20.0, 0.0],
                [20.0, 4.0],
                [14.0, 4.0],
                [14.0, 3.0],
                [6.0, 3.0],
                [6.0, 4.0],
                [0.0, 4.0],
            ],
            &[],
            0.0,
        )
    }

    /// The walls of a line map (e.g. a user's JSON map).
    pub fn from_map(map: &LineMap) -> Self {
        Self {
            walls: map.segments.clone(),
        }
    }

    /// The walls as a line map (what a perfectly surveyed map of the room would hold).
    pub fn to_map(&self) -> LineMap {
        LineMap::new(self.walls.clone())
    }

    /// The smallest box holding every wall; `None` for a room without walls.
    pub fn bounds(&self) -> Option<Bounds> {
        let mut points = self.walls.iter().flat_map(|w| [w.start, w.end]);
        let first = points.next()?;
        Some(points.fold((first, first), |(lo, hi), p| {
            (
                Point2::new(lo.x.min(p.x), lo.y.min(p.y)),
                Point2::new(hi.x.max(p.x), hi.y.max(p.y)),
            )
        }))
    }

    /// Distance from `origin` along the ray at angle `angle` (world frame) to the nearest
    /// wall, if one is hit within `max_range`.
    pub fn ray_cast(&self, origin: &Point2<f64>, angle: f64, max_range: f64) -> Option<f64> {
        let d = Vector2::new(angle.cos(), angle.sin());
        self.walls
            .iter()
            .filter_map(|w| ray_segment(origin, &d, &w.start, &w.end))
            .filter(|&t| t <= max_range)
            .min_by(f64::total_cmp)
    }

    /// Distance from `p` to the nearest wall (m); infinite for a room without walls.
    pub fn clearance(&self, p: &Point2<f64>) -> f64 {
        self.walls
            .iter()
            .map(|w| point_segment_distance(p, &w.start, &w.end))
            .fold(f64::INFINITY, f64::min)
    }

    /// Whether `pose`'s position is at least `margin` from every wall.
    pub fn is_clear(&self, pose: &Pose2<f64>, margin: f64) -> bool {
        self.clearance(&Point2::new(pose.x, pose.y)) >= margin
    }
}

/// The ray parameter `t ≥ 0` at which `origin + t·d` (`|d| = 1`) crosses segment `a b`.
fn ray_segment(
    origin: &Point2<f64>,
    d: &Vector2<f64>,
    a: &Point2<f64>,
    b: &Point2<f64>,
) -> Option<f64> {
    let e = b - a;
    let denom = d.x * e.y - d.y * e.x;
    if denom.abs() < 1e-12 {
        return None;
    }
    let w = a - origin;
    let t = (w.x * e.y - w.y * e.x) / denom;
    let s = (w.x * d.y - w.y * d.x) / denom;
    (t >= 0.0 && (0.0..=1.0).contains(&s)).then_some(t)
}

/// Distance from `p` to segment `a b`.
pub fn point_segment_distance(p: &Point2<f64>, a: &Point2<f64>, b: &Point2<f64>) -> f64 {
    let e = b - a;
    let len2 = e.norm_squared();
    let s = if len2 > 0.0 {
        ((p - a).dot(&e) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p - (a + e * s)).norm()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rays_hit_the_nearest_wall() {
        let room = Room::paper();
        let o = Point2::new(1.0, 1.0);
        let close = |a: Option<f64>, b: f64| (a.unwrap() - b).abs() < 1e-12;
        assert!(close(room.ray_cast(&o, 0.0, 10.0), 5.0));
        assert!(close(
            room.ray_cast(&o, std::f64::consts::FRAC_PI_2, 10.0),
            3.0
        ));
        assert!(close(room.ray_cast(&o, std::f64::consts::PI, 10.0), 1.0));
        assert!(close(
            room.ray_cast(&o, std::f64::consts::FRAC_PI_4, 10.0),
            3.0 * std::f64::consts::SQRT_2
        ));
        assert_eq!(room.ray_cast(&o, 0.0, 4.0), None);
        // A pillar occludes the wall behind it.
        let l = Room::l_shaped();
        assert!(close(l.ray_cast(&Point2::new(1.0, 2.0), 0.0, 20.0), 1.3));
        assert!(close(
            Room::corridor().ray_cast(&Point2::new(10.0, 1.0), -std::f64::consts::FRAC_PI_2, 8.0),
            1.0
        ));
    }

    #[test]
    fn bounds_and_clearance() {
        let (lo, hi) = Room::l_shaped().bounds().unwrap();
        assert_eq!((lo, hi), (Point2::new(0.0, 0.0), Point2::new(10.0, 8.0)));
        assert!((Room::paper().clearance(&Point2::new(1.0, 0.5)) - 0.5).abs() < 1e-12);
        assert!(Room::paper().is_clear(&Pose2::new(3.0, 2.0, 0.0), 1.9));
        assert!(!Room::paper().is_clear(&Pose2::new(3.0, 2.0, 0.0), 2.1));
        assert_eq!(Room { walls: vec![] }.bounds(), None);
    }
}
