//! Synthetic rooms and line observations shared by the map, matching and localizer tests.
#![allow(dead_code)] // each test crate uses a different part

#[path = "../rng_support/mod.rs"]
mod rng_support;

use ekf_core::{Line, Pose2};
use lrf_lines::ObservedLine;
use nalgebra::{Matrix2, Point2};
pub use rng_support::Rng;

/// A wall from one end point to the other (world frame).
pub type Wall = (Point2<f64>, Point2<f64>);

/// The four walls of the axis-aligned rectangle `[x0, x1] × [y0, y1]`, counter-clockwise
/// from the bottom wall.
pub fn rect_room(x0: f64, y0: f64, x1: f64, y1: f64) -> Vec<Wall> {
    let p = |x, y| Point2::new(x, y);
    vec![
        (p(x0, y0), p(x1, y0)),
        (p(x1, y0), p(x1, y1)),
        (p(x1, y1), p(x0, y1)),
        (p(x0, y1), p(x0, y0)),
    ]
}

/// Noise of a synthetic observation: standard deviations of `r` (m) and `ψ` (rad). The
/// observed line's covariance is `diag(σ_r², σ_ψ²)`.
#[derive(Debug, Clone, Copy)]
pub struct LineNoise {
    pub sigma_r: f64,
    pub sigma_psi: f64,
}

pub const NOISE: LineNoise = LineNoise {
    sigma_r: 0.01,
    sigma_psi: 0.005,
};

/// The part `[f0, f1]` (fractions of its length) of `wall` as seen from `sensor` (world
/// pose of the laser), with `(r, ψ)` perturbed by `noise` if `rng` is given. The end
/// points are the part's ends projected onto the (perturbed) line.
pub fn observe_part(
    wall: &Wall,
    f0: f64,
    f1: f64,
    sensor: &Pose2<f64>,
    noise: LineNoise,
    rng: Option<&mut Rng>,
) -> ObservedLine {
    let at = |f: f64| wall.0 + (wall.1 - wall.0) * f;
    let a = sensor.inverse_transform_point(&at(f0));
    let b = sensor.inverse_transform_point(&at(f1));
    let mut line = Line::from_segment(&a, &b).unwrap();
    if let Some(rng) = rng {
        line = Line::new(
            line.rho + noise.sigma_r * rng.normal_floored(),
            line.beta + noise.sigma_psi * rng.normal_floored(),
        )
        .unwrap();
    }
    ObservedLine {
        line,
        covariance: Matrix2::new(
            noise.sigma_r * noise.sigma_r,
            0.0,
            0.0,
            noise.sigma_psi * noise.sigma_psi,
        ),
        start: line.project(&a),
        end: line.project(&b),
        num_points: 50,
    }
}

/// Every wall seen whole from `sensor`, noise-free, with the covariance of `noise`.
pub fn observe_all(walls: &[Wall], sensor: &Pose2<f64>, noise: LineNoise) -> Vec<ObservedLine> {
    walls
        .iter()
        .map(|w| observe_part(w, 0.0, 1.0, sensor, noise, None))
        .collect()
}

/// The map of `walls` (exact segments).
pub fn map_of(walls: &[Wall]) -> lrf_lines::LineMap {
    lrf_lines::LineMap::new(
        walls
            .iter()
            .map(|(a, b)| lrf_lines::MapSegment::from_points(*a, *b).unwrap())
            .collect(),
    )
}

/// The beam geometry of a simulated scanner.
#[derive(Debug, Clone, Copy)]
pub struct Beams {
    /// Bearing of the first beam in the sensor frame (rad).
    pub angle_min: f64,
    /// Step between beams (rad).
    pub increment: f64,
    /// Number of beams.
    pub count: usize,
    /// Beams that hit nothing within this range read it (invalid).
    pub range_max: f64,
}

/// A laser scan ray-cast against `walls` from `sensor` (world pose of the laser), with
/// Gaussian range noise `sigma` (m) if `rng` is given.
pub fn ray_cast(
    walls: &[Wall],
    sensor: &Pose2<f64>,
    beams: &Beams,
    sigma: f64,
    mut rng: Option<&mut Rng>,
) -> Vec<f32> {
    let range_max = beams.range_max;
    (0..beams.count)
        .map(|i| {
            let phi = sensor.theta + beams.angle_min + i as f64 * beams.increment;
            let d = nalgebra::Vector2::new(phi.cos(), phi.sin());
            let o = Point2::new(sensor.x, sensor.y);
            let mut best = range_max;
            for (p, q) in walls {
                let e = q - p;
                let denom = d.x * e.y - d.y * e.x;
                if denom.abs() < 1e-12 {
                    continue;
                }
                let w = p - o;
                let t = (w.x * e.y - w.y * e.x) / denom;
                let u = (w.x * d.y - w.y * d.x) / denom;
                if t > 0.0 && (0.0..=1.0).contains(&u) {
                    best = best.min(t);
                }
            }
            if best < range_max {
                if let Some(rng) = rng.as_deref_mut() {
                    best += sigma * rng.normal_floored();
                }
            }
            best as f32
        })
        .collect()
}
