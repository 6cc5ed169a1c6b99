//! Planar poses and lines in normal form, and their transforms between frames.
//!
//! A line is `x cos β + y sin β = ρ` with `ρ ≥ 0` and `β` in (−π, π] (paper eqs. 14–15).

use crate::validate::finite;
use crate::{wrap_angle, Error, Real};
use nalgebra::{Point2, Vector3};

/// A planar pose `(x, y, θ)`: position in metres, heading in radians, wrapped to (−π, π].
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
pub struct Pose2<T> {
    /// x coordinate (m).
    pub x: T,
    /// y coordinate (m).
    pub y: T,
    /// Heading (rad), counter-clockwise from the x axis of the parent frame.
    pub theta: T,
}

impl<T: Real> Pose2<T> {
    /// A pose; `theta` is wrapped to (−π, π].
    pub fn new(x: T, y: T, theta: T) -> Self {
        Self {
            x,
            y,
            theta: wrap_angle(theta),
        }
    }

    /// The identity pose (0, 0, 0).
    pub fn identity() -> Self {
        Self::new(T::zero(), T::zero(), T::zero())
    }

    /// Fails with [`Error::NonFinite`] unless all three components are finite.
    pub fn validated(self, what: &'static str) -> Result<Self, Error> {
        finite(self.x, what)?;
        finite(self.y, what)?;
        finite(self.theta, what)?;
        Ok(self)
    }

    /// The pose as a state vector `[x, y, θ]`.
    pub fn to_vector(&self) -> Vector3<T> {
        Vector3::new(self.x, self.y, self.theta)
    }

    /// The pose from a state vector `[x, y, θ]` (θ wrapped).
    pub fn from_vector(v: &Vector3<T>) -> Self {
        Self::new(v[0], v[1], v[2])
    }

    /// Composition `self ⊕ other`: `other` is expressed in the frame of `self`.
    pub fn compose(&self, other: &Self) -> Self {
        let (s, c) = self.theta.sin_cos();
        Self::new(
            self.x + c * other.x - s * other.y,
            self.y + s * other.x + c * other.y,
            self.theta + other.theta,
        )
    }

    /// The inverse pose: `p.compose(&p.inverse())` is the identity.
    pub fn inverse(&self) -> Self {
        let (s, c) = self.theta.sin_cos();
        Self::new(
            -c * self.x - s * self.y,
            s * self.x - c * self.y,
            -self.theta,
        )
    }

    /// Maps a point from this pose's frame into the parent frame.
    pub fn transform_point(&self, p: &Point2<T>) -> Point2<T> {
        let (s, c) = self.theta.sin_cos();
        Point2::new(self.x + c * p.x - s * p.y, self.y + s * p.x + c * p.y)
    }

    /// Maps a point from the parent frame into this pose's frame.
    pub fn inverse_transform_point(&self, p: &Point2<T>) -> Point2<T> {
        let (s, c) = self.theta.sin_cos();
        let (dx, dy) = (p.x - self.x, p.y - self.y);
        Point2::new(c * dx + s * dy, -s * dx + c * dy)
    }
}

/// A line in normal form `x cos β + y sin β = ρ`, `ρ ≥ 0`, `β` in (−π, π].
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
pub struct Line<T> {
    /// Distance from the origin to the line, ρ ≥ 0 (m).
    pub rho: T,
    /// Direction of the line's normal from the origin, β in (−π, π] (rad).
    pub beta: T,
}

impl<T: Real> Line<T> {
    /// A line from `(ρ, β)`. A negative `ρ` is normalised to `(−ρ, β + π)`, the same
    /// line. Fails if either value is not finite.
    pub fn new(rho: T, beta: T) -> Result<Self, Error> {
        finite(rho, "line rho")?;
        finite(beta, "line beta")?;
        Ok(Self::normalized(rho, beta))
    }

    /// `(ρ, β)` normalised to `ρ ≥ 0`, `β` wrapped; `ρ = 0` keeps `β`.
    pub(crate) fn normalized(rho: T, beta: T) -> Self {
        if rho < T::zero() {
            Self {
                rho: -rho,
                beta: wrap_angle(beta + T::pi()),
            }
        } else {
            Self {
                rho,
                beta: wrap_angle(beta),
            }
        }
    }

    /// The infinite line through two distinct points. Fails if the points coincide or
    /// are not finite.
    pub fn from_segment(a: &Point2<T>, b: &Point2<T>) -> Result<Self, Error> {
        for v in [a.x, a.y, b.x, b.y] {
            finite(v, "segment end point")?;
        }
        let (dx, dy) = (b.x - a.x, b.y - a.y);
        let len = (dx * dx + dy * dy).sqrt();
        if len <= T::zero() {
            return Err(Error::OutOfRange {
                what: "segment length",
                expected: "> 0 (distinct end points)",
            });
        }
        // The normal is the direction rotated by −90°; ρ is the projection of a point on it.
        let beta = (-dx).atan2(dy);
        let rho = a.x * beta.cos() + a.y * beta.sin();
        Ok(Self::normalized(rho, beta))
    }

    /// Signed distance of a point from the line, `x cos β + y sin β − ρ`.
    pub fn signed_distance(&self, p: &Point2<T>) -> T {
        p.x * self.beta.cos() + p.y * self.beta.sin() - self.rho
    }

    /// The orthogonal projection of a point onto the line.
    pub fn project(&self, p: &Point2<T>) -> Point2<T> {
        let d = self.signed_distance(p);
        Point2::new(p.x - d * self.beta.cos(), p.y - d * self.beta.sin())
    }

    /// This line (given in the parent frame) expressed in the frame at pose `frame`
    /// (paper eqs. 17–18 with the frame's full pose):
    /// `C = ρ − x_f cos β − y_f sin β`, `r = |C|`, `ψ = β − θ_f (+ π if C < 0)`.
    pub fn to_frame(&self, frame: &Pose2<T>) -> Self {
        let c = self.rho - frame.x * self.beta.cos() - frame.y * self.beta.sin();
        Self::normalized(c, self.beta - frame.theta)
    }

    /// This line (given in the frame at pose `frame`) expressed in the parent frame; the
    /// inverse of [`Line::to_frame`].
    pub fn from_frame(&self, frame: &Pose2<T>) -> Self {
        let beta = self.beta + frame.theta;
        let rho = self.rho + frame.x * beta.cos() + frame.y * beta.sin();
        Self::normalized(rho, beta)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::f64::consts::{FRAC_PI_2, PI};
    use proptest::prelude::*;

    #[test]
    fn segment_to_line_known_answers() {
        // The vertical wall x = 2: normal along +x.
        let l = Line::from_segment(&Point2::new(2.0_f64, -1.0), &Point2::new(2.0, 5.0)).unwrap();
        assert!((l.rho - 2.0).abs() < 1e-12 && l.beta.abs() < 1e-12);
        // The same wall given in the other order is the same line.
        let l2 = Line::from_segment(&Point2::new(2.0_f64, 5.0), &Point2::new(2.0, -1.0)).unwrap();
        assert!((l2.rho - 2.0).abs() < 1e-12 && l2.beta.abs() < 1e-12);
        // y = −3: normal along −y.
        let l3 = Line::from_segment(&Point2::new(0.0_f64, -3.0), &Point2::new(1.0, -3.0)).unwrap();
        assert!((l3.rho - 3.0).abs() < 1e-12 && (l3.beta + FRAC_PI_2).abs() < 1e-12);
        assert!(Line::from_segment(&Point2::new(1.0, 1.0), &Point2::new(1.0, 1.0)).is_err());
        assert!(Line::new(f64::NAN, 0.0).is_err());
    }

    #[test]
    fn to_frame_flips_normal_when_origin_crosses() {
        // Wall x = 2 seen from (3, 0, 0): it is behind, at distance 1, normal pointing back.
        let l = Line::new(2.0_f64, 0.0)
            .unwrap()
            .to_frame(&Pose2::new(3.0, 0.0, 0.0));
        assert!((l.rho - 1.0).abs() < 1e-12 && (l.beta - PI).abs() < 1e-12);
        // Seen from (0, 0, π/2): 2 m away, to the robot's right (ψ = −π/2).
        let l = Line::new(2.0, 0.0)
            .unwrap()
            .to_frame(&Pose2::new(0.0, 0.0, FRAC_PI_2));
        assert!((l.rho - 2.0).abs() < 1e-12 && (l.beta + FRAC_PI_2).abs() < 1e-12);
    }

    fn pose() -> impl Strategy<Value = Pose2<f64>> {
        (-10.0..10.0, -10.0..10.0, -PI..PI).prop_map(|(x, y, t)| Pose2::new(x, y, t))
    }

    proptest! {
        #[test]
        fn frame_round_trip(rho in 0.0..20.0, beta in -PI..PI, f in pose()) {
            let l = Line::new(rho, beta).unwrap();
            let back = l.to_frame(&f).from_frame(&f);
            prop_assert!((back.rho - l.rho).abs() < 1e-9);
            prop_assert!(crate::angle_diff(back.beta, l.beta).abs() < 1e-9 || l.rho < 1e-9);
            prop_assert!(back.rho >= 0.0 && back.beta > -PI && back.beta <= PI);
        }

        #[test]
        fn points_on_line_stay_on_line(rho in 0.0..20.0, beta in -PI..PI, s in -5.0..5.0, f in pose()) {
            let l = Line::new(rho, beta).unwrap();
            let p = Point2::new(rho * beta.cos() - s * beta.sin(), rho * beta.sin() + s * beta.cos());
            prop_assert!(l.signed_distance(&p).abs() < 1e-9);
            let local = l.to_frame(&f);
            prop_assert!(local.signed_distance(&f.inverse_transform_point(&p)).abs() < 1e-9);
        }

        #[test]
        fn compose_inverse_is_identity(a in pose(), b in pose()) {
            let i = a.compose(&a.inverse());
            prop_assert!(i.x.abs() < 1e-9 && i.y.abs() < 1e-9 && i.theta.abs() < 1e-12);
            let p = Point2::new(1.5, -0.5);
            let q = a.compose(&b).transform_point(&p);
            let q2 = a.transform_point(&b.transform_point(&p));
            prop_assert!((q - q2).norm() < 1e-9);
        }
    }
}
