//! Measurement models `h(x)` with their Jacobians `H`: compass heading (paper eq. 16, last
//! row), a laser line (eqs. 17–18 with the laser's mounting pose; corrected `H` of eq. 13)
//! and an absolute position (GPS).

use crate::validate::{covariance, finite, non_negative};
use crate::{angle_diff, wrap_angle, Error, Line, Pose2, Real};
use nalgebra::{Matrix1, Matrix1x3, Matrix2, Matrix2x3, SMatrix, SVector, Vector1, Vector2};

/// A measurement of dimension `M` the filter can fuse.
pub trait Measurement<T: Real, const M: usize> {
    /// The measured value `z`.
    fn measured(&self) -> SVector<T, M>;
    /// The predicted measurement `h(x)` and its Jacobian `H = ∂h/∂(x, y, θ)` at `pose`.
    fn predict(&self, pose: &Pose2<T>) -> (SVector<T, M>, SMatrix<T, M, 3>);
    /// The measurement-noise covariance `R`.
    fn noise(&self) -> SMatrix<T, M, M>;
    /// The innovation `z − h(x)`, with angular components wrapped.
    fn residual(&self, z: &SVector<T, M>, predicted: &SVector<T, M>) -> SVector<T, M>;
}

/// Converts a raw compass bearing (clockwise from magnetic north, as the CMPS03 reports
/// it) to the filter's heading: `θ = wrap(π/2 − (bearing + declination)) + map_offset`,
/// wrapped. `declination` is east-positive (true north = magnetic north + declination);
/// `map_offset` rotates the ENU heading into the map frame: 0 when the map's x axis
/// points east, −π/2 when it points north. All in radians.
pub fn heading_from_compass_bearing<T: Real>(bearing: T, declination: T, map_offset: T) -> T {
    wrap_angle(wrap_angle(T::frac_pi_2() - (bearing + declination)) + map_offset)
}

/// The two offsets that turn a raw compass bearing into a map heading; see
/// [`heading_from_compass_bearing`] for the signs.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
pub struct CompassCalibration<T> {
    /// Magnetic declination, east-positive (rad).
    pub declination: T,
    /// Rotation from the ENU frame to the map frame (rad), added to the ENU heading.
    pub map_offset: T,
}

impl<T: Real> CompassCalibration<T> {
    /// The map heading θ for a raw bearing (rad, clockwise from magnetic north).
    pub fn heading(&self, bearing: T) -> T {
        heading_from_compass_bearing(bearing, self.declination, self.map_offset)
    }
}

/// A compass heading measurement `φ` of the robot's heading: `h(x) = θ`, `H = [0 0 1]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Compass<T> {
    /// Measured heading in the map frame (rad), wrapped.
    pub heading: T,
    /// Its variance (rad²). The paper's "0.1° accuracy" is (0.1°)² = 3.05e-6 rad²
    /// (docs/ERRATA.md 3); a real CMPS03 is good to a few degrees.
    pub variance: T,
}

impl<T: Real> Compass<T> {
    /// A heading (rad, map frame) with its variance (rad², > 0).
    pub fn new(heading: T, variance: T) -> Result<Self, Error> {
        finite(heading, "compass heading")?;
        non_negative(variance, "compass variance")?;
        if variance == T::zero() {
            return Err(Error::NotPositiveDefinite {
                what: "compass variance",
            });
        }
        Ok(Self {
            heading: wrap_angle(heading),
            variance,
        })
    }
}

impl<T: Real> Measurement<T, 1> for Compass<T> {
    fn measured(&self) -> Vector1<T> {
        Vector1::new(self.heading)
    }
    fn predict(&self, pose: &Pose2<T>) -> (Vector1<T>, Matrix1x3<T>) {
        (
            Vector1::new(pose.theta),
            Matrix1x3::new(T::zero(), T::zero(), T::one()),
        )
    }
    fn noise(&self) -> Matrix1<T> {
        Matrix1::new(self.variance)
    }
    fn residual(&self, z: &Vector1<T>, predicted: &Vector1<T>) -> Vector1<T> {
        Vector1::new(angle_diff(z[0], predicted[0]))
    }
}

/// A laser line observed in the sensor frame, `(r, ψ)` with its 2×2 covariance, matched to
/// a map line `(ρ, β)` in the world frame; the laser sits at `mount` in the robot frame.
///
/// With the sensor pose `s = x ⊕ mount`:
/// `C = ρ − x_s cos β − y_s sin β`, `r̂ = |C|`, `ψ̂ = β − θ_s (+π if C < 0)` (eqs. 17–18;
/// the paper's `+π/2` is its SICK mounting, `mount.theta = −π/2`). The Jacobian is
/// `∂r̂/∂(x, y) = −sign(C)(cos β, sin β)` (docs/ERRATA.md 2: the paper prints `−C cos β`),
/// `∂r̂/∂θ = sign(C)·∂C/∂θ` (zero for a laser at the robot origin), `∂ψ̂/∂(x, y, θ) = (0, 0, −1)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LaserLine<T> {
    /// The observed line `(r, ψ)` in the sensor frame.
    pub observed: Line<T>,
    /// Covariance of `(r, ψ)`, (m², m·rad, rad²).
    pub covariance: Matrix2<T>,
    /// The matched map line `(ρ, β)` in the world frame.
    pub map_line: Line<T>,
    /// The laser's mounting pose in the robot frame.
    pub mount: Pose2<T>,
}

impl<T: Real> LaserLine<T> {
    /// Checks that every value is finite and the covariance is symmetric positive definite.
    pub fn new(
        observed: Line<T>,
        covariance_rpsi: Matrix2<T>,
        map_line: Line<T>,
        mount: Pose2<T>,
    ) -> Result<Self, Error> {
        finite(observed.rho, "observed line r")?;
        finite(observed.beta, "observed line psi")?;
        finite(map_line.rho, "map line rho")?;
        finite(map_line.beta, "map line beta")?;
        mount.validated("laser mount")?;
        covariance(&covariance_rpsi, "line covariance")?;
        Ok(Self {
            observed,
            covariance: covariance_rpsi,
            map_line,
            mount,
        })
    }

    /// The laser's position `(x_s, y_s)` in the world when the robot is at `pose`.
    fn sensor_position(&self, pose: &Pose2<T>) -> (T, T) {
        let (st, ct) = pose.theta.sin_cos();
        let (mx, my) = (self.mount.x, self.mount.y);
        (pose.x + ct * mx - st * my, pose.y + st * mx + ct * my)
    }

    /// The Jacobian of `h = (r̂, ψ̂)` with respect to the map line `(ρ, β)` at `pose`, for
    /// a map whose walls are uncertain (see [`crate::Considered`]):
    /// `∂r̂/∂ρ = sign(C)`, `∂r̂/∂β = sign(C)(x_s sin β − y_s cos β)`, `∂ψ̂/∂ρ = 0`,
    /// `∂ψ̂/∂β = 1`, with `C = ρ − x_s cos β − y_s sin β`. It is invertible: a line seen
    /// from a known pose gives the map line back.
    pub fn map_jacobian(&self, pose: &Pose2<T>) -> Matrix2<T> {
        let (sb, cb) = self.map_line.beta.sin_cos();
        let (xs, ys) = self.sensor_position(pose);
        let c = self.map_line.rho - xs * cb - ys * sb;
        let sign = if c < T::zero() { -T::one() } else { T::one() };
        Matrix2::new(sign, sign * (xs * sb - ys * cb), T::zero(), T::one())
    }
}

impl<T: Real> Measurement<T, 2> for LaserLine<T> {
    fn measured(&self) -> Vector2<T> {
        Vector2::new(self.observed.rho, self.observed.beta)
    }
    fn predict(&self, pose: &Pose2<T>) -> (Vector2<T>, Matrix2x3<T>) {
        let (st, ct) = pose.theta.sin_cos();
        let (sb, cb) = self.map_line.beta.sin_cos();
        let (mx, my) = (self.mount.x, self.mount.y);
        let (xs, ys) = self.sensor_position(pose);
        // The derivative of the sensor's position with respect to θ.
        let (dxs, dys) = (-st * mx - ct * my, ct * mx - st * my);
        let c = self.map_line.rho - xs * cb - ys * sb;
        let psi = self.map_line.beta - pose.theta - self.mount.theta;
        let (r_hat, psi_hat, sign) = if c < T::zero() {
            (-c, psi + T::pi(), -T::one())
        } else {
            (c, psi, T::one())
        };
        let dc_dtheta = -(dxs * cb + dys * sb);
        let h = Matrix2x3::new(
            -sign * cb,
            -sign * sb,
            sign * dc_dtheta,
            T::zero(),
            T::zero(),
            -T::one(),
        );
        (Vector2::new(r_hat, wrap_angle(psi_hat)), h)
    }
    fn noise(&self) -> Matrix2<T> {
        self.covariance
    }
    fn residual(&self, z: &Vector2<T>, predicted: &Vector2<T>) -> Vector2<T> {
        Vector2::new(z[0] - predicted[0], angle_diff(z[1], predicted[1]))
    }
}

/// An absolute position measurement (a GPS fix projected into the map frame):
/// `h(x) = (x, y)`, `H = [[1 0 0], [0 1 0]]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Position<T> {
    /// Measured x (m).
    pub x: T,
    /// Measured y (m).
    pub y: T,
    /// Its 2×2 covariance (m²).
    pub covariance: Matrix2<T>,
}

impl<T: Real> Position<T> {
    /// Checks that the values are finite and the covariance symmetric positive definite.
    pub fn new(x: T, y: T, covariance_xy: Matrix2<T>) -> Result<Self, Error> {
        finite(x, "position x")?;
        finite(y, "position y")?;
        covariance(&covariance_xy, "position covariance")?;
        Ok(Self {
            x,
            y,
            covariance: covariance_xy,
        })
    }
}

impl<T: Real> Measurement<T, 2> for Position<T> {
    fn measured(&self) -> Vector2<T> {
        Vector2::new(self.x, self.y)
    }
    fn predict(&self, pose: &Pose2<T>) -> (Vector2<T>, Matrix2x3<T>) {
        let (o, i) = (T::zero(), T::one());
        (
            Vector2::new(pose.x, pose.y),
            Matrix2x3::new(i, o, o, o, i, o),
        )
    }
    fn noise(&self) -> Matrix2<T> {
        self.covariance
    }
    fn residual(&self, z: &Vector2<T>, predicted: &Vector2<T>) -> Vector2<T> {
        z - predicted
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::f64::consts::{FRAC_PI_2, PI};

    #[test]
    fn compass_bearing_conventions() {
        let d = |deg: f64| deg.to_radians();
        // Bearing 0 (north) is θ = π/2 in ENU; bearing 90° (east) is θ = 0.
        assert!((heading_from_compass_bearing(0.0, 0.0, 0.0) - FRAC_PI_2).abs() < 1e-12);
        assert!(heading_from_compass_bearing(d(90.0), 0.0, 0.0).abs() < 1e-12);
        // West (270°) is θ = π; south (180°) is −π/2.
        assert!((heading_from_compass_bearing(d(270.0), 0.0, 0.0) - PI).abs() < 1e-12);
        assert!((heading_from_compass_bearing(d(180.0), 0.0, 0.0) + FRAC_PI_2).abs() < 1e-12);
        // 10° east declination: magnetic bearing 80° is true east.
        assert!(heading_from_compass_bearing(d(80.0), d(10.0), 0.0).abs() < 1e-12);
        // A map whose x axis points north: east in ENU is −90° in the map, so offset −π/2.
        let cal = CompassCalibration {
            declination: 0.0,
            map_offset: -FRAC_PI_2,
        };
        assert!((cal.heading(d(90.0)) + FRAC_PI_2).abs() < 1e-12);
        assert!(cal.heading(0.0).abs() < 1e-12);
    }

    #[test]
    fn paper_mounting_reproduces_eq_18() {
        // Eq. 18 with the SICK's 0° to the right: ψ̂ = β − (θ − π/2) + (C < 0 ? π : 0).
        let map_line = Line::new(4.0, 0.3).unwrap();
        let mount = Pose2::new(0.0, 0.0, -FRAC_PI_2);
        let m = LaserLine::new(
            Line::new(1.0, 0.0).unwrap(),
            Matrix2::identity(),
            map_line,
            mount,
        )
        .unwrap();
        for (x, y, th) in [(1.0, 0.5, 0.2), (6.0, 2.0, -2.5)] {
            let (z, _) = m.predict(&Pose2::new(x, y, th));
            let c: f64 = 4.0 - x * 0.3_f64.cos() - y * 0.3_f64.sin();
            let psi = 0.3 - (th - FRAC_PI_2) + if c < 0.0 { PI } else { 0.0 };
            assert!((z[0] - c.abs()).abs() < 1e-12);
            assert!(angle_diff(z[1], psi).abs() < 1e-12);
        }
    }

    #[test]
    fn invalid_measurements_are_refused() {
        assert_eq!(
            Compass::new(f64::NAN, 1.0),
            Err(Error::NonFinite {
                what: "compass heading"
            })
        );
        assert_eq!(
            Compass::new(0.0, -1.0),
            Err(Error::NegativeVariance {
                what: "compass variance"
            })
        );
        let l = Line::new(1.0, 0.0).unwrap();
        let asym = Matrix2::new(1.0, 0.5, 0.0, 1.0);
        assert_eq!(
            LaserLine::new(l, asym, l, Pose2::identity()),
            Err(Error::NotSymmetric {
                what: "line covariance"
            })
        );
        let indef = Matrix2::new(1.0, 2.0, 2.0, 1.0);
        assert_eq!(
            LaserLine::new(l, indef, l, Pose2::identity()),
            Err(Error::NotPositiveDefinite {
                what: "line covariance"
            })
        );
        assert!(Position::new(0.0, f64::INFINITY, Matrix2::identity()).is_err());
    }
}
