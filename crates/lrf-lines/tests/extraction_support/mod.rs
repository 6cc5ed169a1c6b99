//! Test support for the extraction tests and benchmark: a seeded normal RNG, a ray caster
//! against wall segments, the synthetic rooms, and the list of wall pieces a scan shows.
#![allow(dead_code)] // Each test binary uses a different part of this module.

#[path = "../rng_support/mod.rs"]
mod rng_support;

use ekf_core::{Line, Pose2};
use nalgebra::Point2;
pub use rng_support::Rng;

/// A wall (or a face of a piece of furniture) from `a` to `b` in the world frame.
#[derive(Debug, Clone, Copy)]
pub struct Wall {
    pub a: Point2<f64>,
    pub b: Point2<f64>,
}

/// Walls of a closed polygon, in order.
pub fn polygon(corners: &[(f64, f64)]) -> Vec<Wall> {
    (0..corners.len())
        .map(|i| {
            let (a, b) = (corners[i], corners[(i + 1) % corners.len()]);
            Wall {
                a: Point2::new(a.0, a.1),
                b: Point2::new(b.0, b.1),
            }
        })
        .collect()
}

/// An axis-aligned box (pillar, table, cabinet) with centre `(cx, cy)` and size `w × h`.
pub fn block(cx: f64, cy: f64, w: f64, h: f64) -> Vec<Wall> {
    let (x0, x1, y0, y1) = (cx - w / 2.0, cx + w / 2.0, cy - h / 2.0, cy + h / 2.0);
    polygon(&[(x0, y0), (x1, y0), (x1, y1), (x0, y1)])
}

/// Beam geometry of a simulated scanner.
#[derive(Debug, Clone, Copy)]
pub struct Scanner {
    pub angle_min: f64,
    pub angle_increment: f64,
    pub beams: usize,
    pub range_max: f64,
}

impl Scanner {
    /// A scanner sweeping `fov` (rad) centred ahead with `step` (rad) between beams.
    pub fn new(fov: f64, step: f64) -> Self {
        let beams = (fov / step).round() as usize + 1;
        Self {
            angle_min: -fov / 2.0,
            angle_increment: step,
            beams,
            range_max: 30.0,
        }
    }

    /// `ranges` as a scan of this scanner (range_min 5 cm).
    pub fn scan<'a>(&self, ranges: &'a [f32]) -> lrf_lines::LaserScan<'a> {
        lrf_lines::LaserScan {
            angle_min: self.angle_min,
            angle_increment: self.angle_increment,
            range_min: 0.05,
            range_max: self.range_max,
            ranges,
        }
    }

    /// The bearing of beam `i`.
    pub fn angle(&self, i: usize) -> f64 {
        self.angle_min + i as f64 * self.angle_increment
    }
}

/// The first wall hit by the ray from `pose` along bearing `phi` (sensor frame):
/// `(range, wall index)`.
pub fn cast(walls: &[Wall], pose: &Pose2<f64>, phi: f64) -> Option<(f64, usize)> {
    let a = pose.theta + phi;
    let (dx, dy) = (a.cos(), a.sin());
    let mut best: Option<(f64, usize)> = None;
    for (k, w) in walls.iter().enumerate() {
        let (ex, ey) = (w.b.x - w.a.x, w.b.y - w.a.y);
        let den = dx * ey - dy * ex;
        if den.abs() < 1e-12 {
            continue;
        }
        let (ox, oy) = (w.a.x - pose.x, w.a.y - pose.y);
        let t = (ox * ey - oy * ex) / den; // along the ray
        let s = (ox * dy - oy * dx) / den; // along the wall
        if t > 1e-9 && (0.0..=1.0).contains(&s) && best.is_none_or(|(bt, _)| t < bt) {
            best = Some((t, k));
        }
    }
    best
}

/// A noisy scan: each beam is cast at its bearing plus N(0, σ_φ²) and its range gets
/// N(0, σ_ρ²); beams that hit nothing read `range_max` (the overflow code).
pub fn simulate(
    walls: &[Wall],
    pose: &Pose2<f64>,
    scanner: &Scanner,
    sigma_range: f64,
    sigma_bearing: f64,
    rng: &mut Rng,
) -> Vec<f32> {
    (0..scanner.beams)
        .map(|i| {
            let phi = scanner.angle(i) + sigma_bearing * rng.normal();
            match cast(walls, pose, phi) {
                Some((t, _)) => (t + sigma_range * rng.normal()) as f32,
                None => scanner.range_max as f32,
            }
        })
        .collect()
}

/// A visible piece of a wall: consecutive beams hitting the same wall with noise-free
/// points at most `max_gap(ρ_a, ρ_b)` apart (`ρ` their ranges).
#[derive(Debug, Clone, Copy)]
pub struct Piece {
    pub wall: usize,
    /// The wall's line in the sensor frame.
    pub line: Line<f64>,
    pub num_points: usize,
    /// Distance between the first and last noise-free points (m).
    pub length: f64,
}

/// The visible wall pieces in beam order, from noise-free ray casting.
pub fn visible_pieces(
    walls: &[Wall],
    pose: &Pose2<f64>,
    scanner: &Scanner,
    max_gap: &dyn Fn(f64, f64) -> f64,
) -> Vec<Piece> {
    let mut pieces: Vec<(Piece, Point2<f64>, Point2<f64>)> = Vec::new();
    let mut open = false;
    for i in 0..scanner.beams {
        let phi = scanner.angle(i);
        let Some((t, k)) = cast(walls, pose, phi) else {
            open = false;
            continue;
        };
        let p = Point2::new(t * phi.cos(), t * phi.sin());
        if let Some((piece, first, last)) = pieces.last_mut() {
            let gap = max_gap(last.coords.norm(), t);
            if open && piece.wall == k && (p - *last).norm() <= gap {
                *last = p;
                piece.num_points += 1;
                piece.length = (p - *first).norm();
                continue;
            }
        }
        let world = Line::from_segment(&walls[k].a, &walls[k].b).unwrap();
        pieces.push((
            Piece {
                wall: k,
                line: world.to_frame(pose),
                num_points: 1,
                length: 0.0,
            },
            p,
            p,
        ));
        open = true;
    }
    pieces.into_iter().map(|(p, _, _)| p).collect()
}

/// A named test room: its walls and the sensor pose.
pub struct Room {
    pub name: &'static str,
    pub walls: Vec<Wall>,
    pub pose: Pose2<f64>,
}

/// 6 m × 4 m rectangle.
pub fn rectangle() -> Room {
    Room {
        name: "rectangle",
        walls: polygon(&[(0.0, 0.0), (6.0, 0.0), (6.0, 4.0), (0.0, 4.0)]),
        pose: Pose2::new(2.5, 1.6, 0.4),
    }
}

/// An L: a 7 × 3 m arm and a 3 × 3 m arm; seen from the far end of the long arm, the
/// reflex corner at (3, 3) hides the top of the left wall (an occlusion shadow).
pub fn l_shape() -> Room {
    Room {
        name: "L-shape",
        walls: polygon(&[
            (0.0, 0.0),
            (7.0, 0.0),
            (7.0, 3.0),
            (3.0, 3.0),
            (3.0, 6.0),
            (0.0, 6.0),
        ]),
        pose: Pose2::new(5.5, 1.2, 2.4),
    }
}

/// A 2.4 m wide, 8 m long corridor with a 1 m doorway (nothing behind it: the beams
/// through it read the overflow code) in its left wall.
pub fn corridor() -> Room {
    let w = |a: (f64, f64), b: (f64, f64)| Wall {
        a: Point2::new(a.0, a.1),
        b: Point2::new(b.0, b.1),
    };
    Room {
        name: "corridor",
        walls: vec![
            w((0.0, 0.0), (8.0, 0.0)),
            w((8.0, 0.0), (8.0, 2.4)),
            w((8.0, 2.4), (4.0, 2.4)),
            w((3.0, 2.4), (0.0, 2.4)),
            w((0.0, 2.4), (0.0, 0.0)),
        ],
        pose: Pose2::new(5.0, 1.0, 0.1),
    }
}

/// An 8 × 6 m room with a 0.8 m square pillar whose shadow cuts the far wall in two.
pub fn pillar_room() -> Room {
    let mut walls = polygon(&[(0.0, 0.0), (8.0, 0.0), (8.0, 6.0), (0.0, 6.0)]);
    walls.extend(block(4.2, 3.0, 0.8, 0.8));
    Room {
        name: "pillar room",
        walls,
        pose: Pose2::new(1.5, 3.0, 0.05),
    }
}

/// A furnished 9 × 7 m room for the benchmark: two pillars, a table, a cabinet against a
/// wall, a sofa and four chair legs.
pub fn furnished_room() -> Room {
    let mut walls = polygon(&[(0.0, 0.0), (9.0, 0.0), (9.0, 7.0), (0.0, 7.0)]);
    walls.extend(block(3.0, 4.5, 0.5, 0.5));
    walls.extend(block(6.5, 2.0, 0.5, 0.5));
    walls.extend(block(5.5, 5.0, 1.6, 0.9));
    walls.extend(block(8.7, 3.5, 0.6, 1.8));
    walls.extend(block(2.0, 1.0, 2.0, 0.8));
    for (x, y) in [(4.2, 3.0), (4.6, 3.0), (4.2, 3.4), (4.6, 3.4)] {
        walls.extend(block(x, y, 0.05, 0.05));
    }
    Room {
        name: "furnished room",
        walls,
        pose: Pose2::new(1.2, 3.2, 0.1),
    }
}
