//! Commanded paths (closed loops with rounded corners, as in the paper's Fig. 11) and the
//! distance of a position from them.

use super::room::point_segment_distance;
use nalgebra::{Point2, Vector2};

/// Spacing of the points of a densified path (m).
const SPACING: f64 = 0.02;

/// A closed path: a dense polyline (the last point joins the first) with the arc length
/// at each point.
#[derive(Debug, Clone, PartialEq)]
pub struct Path {
    points: Vec<Point2<f64>>,
    /// `arc[i]`: length from point 0 to point `i` (m); `arc[n]` is the whole loop.
    arc: Vec<f64>,
}

/// Why a path could not be made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PathError {
    /// Too few corners, or corners that coincide.
    #[error("a path needs at least 3 distinct corners")]
    TooFewCorners,
    /// The corner radius does not fit between two corners.
    #[error("corner radius {radius} m does not fit at corner {corner} (its edges are too short or the turn too sharp)")]
    RadiusTooLarge {
        /// The radius asked for (m).
        radius: f64,
        /// The corner (index into the corners).
        corner: usize,
    },
}

impl Path {
    /// The closed polygon through `corners` (in driving order) with each corner replaced
    /// by a circular arc of `radius` tangent to both edges.
    pub fn rounded_polygon(corners: &[Point2<f64>], radius: f64) -> Result<Self, PathError> {
        let n = corners.len();
        if n < 3 || (0..n).any(|i| (corners[(i + 1) % n] - corners[i]).norm() < 1e-9) {
            return Err(PathError::TooFewCorners);
        }
        // Each corner: tangent points in and out and the arc between them.
        let mut arcs = Vec::with_capacity(n);
        for i in 0..n {
            let (p, v, q) = (corners[(i + n - 1) % n], corners[i], corners[(i + 1) % n]);
            let (u1, u2) = ((v - p).normalize(), (q - v).normalize());
            let turn = u1.perp(&u2).atan2(u1.dot(&u2));
            let d = radius * (turn.abs() / 2.0).tan();
            if d > 0.5 * (v - p).norm() || d > 0.5 * (q - v).norm() || turn.abs() > 3.0 {
                return Err(PathError::RadiusTooLarge { radius, corner: i });
            }
            let t_in = v - u1 * d;
            let left = Vector2::new(-u1.y, u1.x) * turn.signum();
            let centre = t_in + left * radius;
            arcs.push((t_in, centre, turn));
        }
        let mut points = Vec::new();
        for (i, &(t_in, centre, turn)) in arcs.iter().enumerate() {
            let r0 = t_in - centre;
            let steps = ((turn.abs() * radius / SPACING).ceil() as usize).max(1);
            for k in 0..=steps {
                let a = turn * k as f64 / steps as f64;
                let (s, c) = a.sin_cos();
                points.push(centre + Vector2::new(c * r0.x - s * r0.y, s * r0.x + c * r0.y));
            }
            // The straight edge to the next arc.
            let from = *points.last().unwrap_or(&t_in);
            let to = arcs[(i + 1) % n].0;
            let len = (to - from).norm();
            let steps = (len / SPACING).ceil() as usize;
            for k in 1..steps {
                points.push(from + (to - from) * (k as f64 / steps as f64));
            }
        }
        Ok(Self::from_points(points))
    }

    fn from_points(points: Vec<Point2<f64>>) -> Self {
        let mut arc = Vec::with_capacity(points.len() + 1);
        let mut s = 0.0;
        arc.push(0.0);
        for i in 0..points.len() {
            s += (points[(i + 1) % points.len()] - points[i]).norm();
            arc.push(s);
        }
        Self { points, arc }
    }

    /// The length of one loop (m).
    pub fn length(&self) -> f64 {
        self.arc[self.points.len()]
    }

    /// The pose at the start of the loop, facing along the path.
    pub fn start_pose(&self) -> ekf_core::Pose2<f64> {
        let (a, b) = (self.point_at(0.0), self.point_at(SPACING));
        ekf_core::Pose2::new(a.x, a.y, (b.y - a.y).atan2(b.x - a.x))
    }

    /// The polyline's points (the last joins the first).
    pub fn points(&self) -> &[Point2<f64>] {
        &self.points
    }

    /// The point at arc length `s` from the start, wrapping around the loop.
    pub fn point_at(&self, s: f64) -> Point2<f64> {
        let s = s.rem_euclid(self.length());
        let i = self.arc.partition_point(|&a| a <= s).saturating_sub(1);
        let i = i.min(self.points.len() - 1);
        let (a, b) = (self.points[i], self.points[(i + 1) % self.points.len()]);
        let seg = self.arc[i + 1] - self.arc[i];
        let f = if seg > 0.0 {
            (s - self.arc[i]) / seg
        } else {
            0.0
        };
        a + (b - a) * f
    }

    /// The arc length of the path point nearest to `p` among those within `window` (m)
    /// ahead of arc length `from` (so a follower's progress never jumps across the loop).
    pub fn progress_near(&self, p: &Point2<f64>, from: f64, window: f64) -> f64 {
        let steps = (window / SPACING).ceil() as usize;
        (0..=steps)
            .map(|k| from + k as f64 * SPACING)
            .min_by(|a, b| {
                let da = (self.point_at(*a) - p).norm_squared();
                let db = (self.point_at(*b) - p).norm_squared();
                da.total_cmp(&db)
            })
            .unwrap_or(from)
    }

    /// Distance from `p` to the path (m).
    pub fn distance(&self, p: &Point2<f64>) -> f64 {
        let n = self.points.len();
        (0..n)
            .map(|i| point_segment_distance(p, &self.points[i], &self.points[(i + 1) % n]))
            .fold(f64::INFINITY, f64::min)
    }
}

/// Pure pursuit (Coulter 1992): steer along the circle through the robot and the path
/// point one look-ahead distance further along, `κ = 2·y_r / ℓ²` with `y_r` the lateral
/// offset of that point in the robot frame.
#[derive(Debug, Clone, PartialEq)]
pub struct PurePursuit {
    /// Look-ahead distance `ℓ` (m).
    pub lookahead: f64,
    /// Forward speed (m/s).
    pub speed: f64,
    /// Largest turn rate commanded (rad/s).
    pub max_turn_rate: f64,
    /// Arc length travelled along the path so far (m; grows past one loop).
    progress: f64,
}

impl PurePursuit {
    /// A follower starting at the path's start.
    pub fn new(lookahead: f64, speed: f64, max_turn_rate: f64) -> Self {
        Self {
            lookahead,
            speed,
            max_turn_rate,
            progress: 0.0,
        }
    }

    /// Starts following at the path point nearest to `pose`.
    pub fn join(&mut self, path: &Path, pose: &ekf_core::Pose2<f64>) {
        let p = Point2::new(pose.x, pose.y);
        self.progress = path.progress_near(&p, 0.0, path.length() - SPACING);
    }

    /// Arc length of the path covered so far (m).
    pub fn progress(&self) -> f64 {
        self.progress
    }

    /// The command `(v, ω)` (m/s, rad/s) for a robot believed to be at `pose`
    /// (`(x, y, θ)`).
    pub fn command(&mut self, path: &Path, pose: &ekf_core::Pose2<f64>) -> (f64, f64) {
        let p = Point2::new(pose.x, pose.y);
        self.progress = path.progress_near(&p, self.progress, 3.0 * self.lookahead);
        let target = path.point_at(self.progress + self.lookahead);
        let (s, c) = pose.theta.sin_cos();
        let (dx, dy) = (target.x - pose.x, target.y - pose.y);
        let (xr, yr) = (c * dx + s * dy, -s * dx + c * dy);
        let l2 = (xr * xr + yr * yr).max(1e-6);
        let kappa = 2.0 * yr / l2;
        let omega = (self.speed * kappa).clamp(-self.max_turn_rate, self.max_turn_rate);
        // Slow down in proportion when the turn rate saturates, so the arc is kept.
        let v = if kappa.abs() > 0.0 {
            self.speed.min(self.max_turn_rate / kappa.abs())
        } else {
            self.speed
        };
        (v, omega)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    fn square(side: f64) -> Vec<Point2<f64>> {
        vec![
            Point2::new(0.0, 0.0),
            Point2::new(side, 0.0),
            Point2::new(side, side),
            Point2::new(0.0, side),
        ]
    }

    #[test]
    fn rounded_square_has_the_right_length_and_shape() {
        let path = Path::rounded_polygon(&square(4.0), 0.5).unwrap();
        // Four straight edges shortened by 2r each plus a full circle of radius r.
        let want = 4.0 * (4.0 - 1.0) + 2.0 * PI * 0.5;
        assert!((path.length() - want).abs() < 1e-3, "{}", path.length());
        assert!(path.distance(&Point2::new(2.0, 0.0)) < 1e-9);
        assert!((path.distance(&Point2::new(2.0, 1.0)) - 1.0).abs() < 1e-9);
        // The corner is cut by r(√2 − 1).
        let cut = path.distance(&Point2::new(4.0, 0.0));
        assert!((cut - 0.5 * (2f64.sqrt() - 1.0)).abs() < 1e-3, "{cut}");
        assert!((path.point_at(path.length() + 1.0) - path.point_at(1.0)).norm() < 1e-9);
    }

    #[test]
    fn bad_paths_are_refused() {
        assert_eq!(
            Path::rounded_polygon(&square(4.0)[..2], 0.5),
            Err(PathError::TooFewCorners)
        );
        assert!(matches!(
            Path::rounded_polygon(&square(1.0), 0.6),
            Err(PathError::RadiusTooLarge { corner: 0, .. })
        ));
    }

    #[test]
    fn pure_pursuit_steers_towards_the_path() {
        let path = Path::rounded_polygon(&square(4.0), 0.5).unwrap();
        let mut f = PurePursuit::new(0.5, 0.3, 1.0);
        // On the first edge heading along it: straight on.
        let (v, w) = f.command(&path, &ekf_core::Pose2::new(1.5, 0.0, 0.0));
        assert!((v - 0.3).abs() < 1e-9 && w.abs() < 1e-6, "{v} {w}");
        // Right of the path (below it): turn left; left of it: turn right.
        let (_, w) = f.command(&path, &ekf_core::Pose2::new(1.6, -0.2, 0.0));
        assert!(w > 0.1, "{w}");
        let (_, w) = f.command(&path, &ekf_core::Pose2::new(1.7, 0.2, 0.0));
        assert!(w < -0.1, "{w}");
        assert!(f.progress() > 1.5);
    }
}
