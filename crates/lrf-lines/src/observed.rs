//! A line extracted from one scan: the measurement the filter fuses.

use ekf_core::{wrap_angle, Error, Line, Pose2};
use nalgebra::{Matrix2, Point2};

/// A line observed in one scan, in the sensor frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ObservedLine {
    /// The line `(r, ψ)` in normal form in the sensor frame (`r ≥ 0`).
    pub line: Line<f64>,
    /// Covariance of `(r, ψ)`: the inverse of the full 2×2 Fisher information of the
    /// weighted fit (m², m·rad, rad²).
    pub covariance: Matrix2<f64>,
    /// First end point of the segment (sensor frame), in scan order.
    pub start: Point2<f64>,
    /// Last end point of the segment (sensor frame), in scan order.
    pub end: Point2<f64>,
    /// Number of scan points the line was fitted to.
    pub num_points: usize,
}

impl ObservedLine {
    /// Fails unless the line, its end points and covariance are finite and the covariance is
    /// symmetric positive definite.
    pub fn validate(&self) -> Result<(), Error> {
        let values = [
            self.line.rho,
            self.line.beta,
            self.start.x,
            self.start.y,
            self.end.x,
            self.end.y,
        ];
        if values
            .iter()
            .chain(self.covariance.iter())
            .any(|v| !v.is_finite())
        {
            return Err(Error::NonFinite {
                what: "observed line",
            });
        }
        let c = &self.covariance;
        let scale = c.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        if (c[(0, 1)] - c[(1, 0)]).abs() > 1e-9 * scale {
            return Err(Error::NotSymmetric {
                what: "observed line covariance",
            });
        }
        if c.cholesky().is_none() {
            return Err(Error::NotPositiveDefinite {
                what: "observed line covariance",
            });
        }
        Ok(())
    }

    /// Length of the segment between its end points (m).
    pub fn length(&self) -> f64 {
        (self.end - self.start).norm()
    }

    /// The line as seen in a frame where its sensor is at `sensor` (a world frame, or
    /// another scan's sensor frame): `ρ = r + x cos β + y sin β`, `β = ψ + θ`, covariance
    /// `J Σ Jᵀ` with `J = [[1, −x sin β + y cos β], [0, 1]]` (the pose taken as exact),
    /// normalised to `ρ ≥ 0`; the end points transformed.
    pub fn seen_from(&self, sensor: &Pose2<f64>) -> Self {
        let beta = wrap_angle(self.line.beta + sensor.theta);
        let (s, c) = (libm::sin(beta), libm::cos(beta));
        let rho = self.line.rho + sensor.x * c + sensor.y * s;
        let j = Matrix2::new(1.0, -sensor.x * s + sensor.y * c, 0.0, 1.0);
        let (line, covariance) = normalized(rho, beta, j * self.covariance * j.transpose());
        Self {
            line,
            covariance,
            start: sensor.transform_point(&self.start),
            end: sensor.transform_point(&self.end),
            num_points: self.num_points,
        }
    }
}

/// `(ρ, β)` with covariance, normalised to `ρ ≥ 0`: `(−ρ, β + π)` flips the sign of the
/// ρ–β covariance.
pub(crate) fn normalized(
    rho: f64,
    beta: f64,
    covariance: Matrix2<f64>,
) -> (Line<f64>, Matrix2<f64>) {
    if rho < 0.0 {
        let flip = Matrix2::new(-1.0, 0.0, 0.0, 1.0);
        (
            Line {
                rho: -rho,
                beta: wrap_angle(beta + core::f64::consts::PI),
            },
            flip * covariance * flip,
        )
    } else {
        (
            Line {
                rho,
                beta: wrap_angle(beta),
            },
            covariance,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn observed(a: Point2<f64>, b: Point2<f64>) -> ObservedLine {
        ObservedLine {
            line: Line::from_segment(&a, &b).unwrap(),
            covariance: Matrix2::new(1e-4, 2e-5, 2e-5, 1e-4),
            start: a,
            end: b,
            num_points: 10,
        }
    }

    proptest! {
        /// Seen from another frame, the end points lie on the line, `ρ ≥ 0`, the
        /// covariance stays symmetric positive definite, and going back gives the line.
        #[test]
        fn seen_from_another_frame_and_back(
            ax in -5.0..5.0f64, ay in -5.0..5.0f64, bx in -5.0..5.0f64, by in -5.0..5.0f64,
            x in -10.0..10.0f64, y in -10.0..10.0f64, t in -3.1..3.1f64,
        ) {
            let (a, b) = (Point2::new(ax, ay), Point2::new(bx, by));
            prop_assume!((b - a).norm() > 0.1);
            let line = observed(a, b);
            let frame = Pose2::new(x, y, t);
            let seen = line.seen_from(&frame);
            prop_assert!(seen.line.rho >= 0.0);
            prop_assert!(seen.line.signed_distance(&seen.start).abs() < 1e-9);
            prop_assert!(seen.line.signed_distance(&seen.end).abs() < 1e-9);
            let c = seen.covariance;
            prop_assert!((c[(0, 1)] - c[(1, 0)]).abs() < 1e-15);
            prop_assert!(c[(0, 0)] > 0.0 && c.determinant() > 0.0);
            let back = seen.seen_from(&frame.inverse());
            prop_assert!((back.line.rho - line.line.rho).abs() < 1e-9);
            prop_assert!(ekf_core::angle_diff(back.line.beta, line.line.beta).abs() < 1e-9);
            prop_assert!((back.start - a).norm() < 1e-9 && (back.end - b).norm() < 1e-9);
            prop_assert!((back.covariance - line.covariance).abs().max() < 1e-12);
        }
    }
}
