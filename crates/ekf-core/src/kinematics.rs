//! Differential-drive kinematics (paper eqs. 1–3) and the motion model's Jacobians.

use crate::validate::{finite, positive};
use crate::{Error, Pose2, Real};
use nalgebra::{Matrix3, Matrix3x2};

/// The robot's wheel geometry. A field missing when deserialized takes the default's
/// (the paper's robot).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(
    feature = "serde",
    serde(
        default,
        deny_unknown_fields,
        bound(deserialize = "T: Real + serde::Deserialize<'de>")
    )
)]
pub struct DiffDrive<T> {
    /// Radius of the driven wheels, `R` (m).
    pub wheel_radius: T,
    /// Distance between the two driven wheels, `L` (m).
    pub track: T,
}

/// Wheel rotational speeds over one sampling period.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WheelSpeeds<T> {
    /// Left wheel speed `ω_L` (rad/s), positive drives the robot forward.
    pub left: T,
    /// Right wheel speed `ω_R` (rad/s), positive drives the robot forward.
    pub right: T,
    /// Sampling period `Δt` (s).
    pub dt: T,
}

/// One step of planar motion: distance `Δs` travelled by the robot's centre along the
/// mid-angle heading, and heading change `Δθ` (paper eq. 2).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Motion<T> {
    /// Distance travelled by the centre of the axle, `Δs` (m), negative when reversing.
    pub ds: T,
    /// Heading change `Δθ` (rad).
    pub dtheta: T,
}

impl<T: Real> WheelSpeeds<T> {
    /// Wheel speeds `(ω_L, ω_R)` held for `dt` seconds. Fails on non-finite values or
    /// `dt ≤ 0`.
    pub fn new(left: T, right: T, dt: T) -> Result<Self, Error> {
        finite(left, "left wheel speed")?;
        finite(right, "right wheel speed")?;
        positive(dt, "dt")?;
        Ok(Self { left, right, dt })
    }

    /// Mean wheel speeds from wheel-angle increments `Δφ_L`, `Δφ_R` (rad) over `dt`
    /// seconds: `ω = Δφ / Δt`. Use this with encoder tick counts converted to radians.
    pub fn from_increments(dphi_left: T, dphi_right: T, dt: T) -> Result<Self, Error> {
        finite(dphi_left, "left wheel increment")?;
        finite(dphi_right, "right wheel increment")?;
        positive(dt, "dt")?;
        Self::new(dphi_left / dt, dphi_right / dt, dt)
    }
}

impl<T: Real> Default for DiffDrive<T> {
    /// The paper's robot ([`DiffDrive::paper`]).
    fn default() -> Self {
        Self::paper()
    }
}

impl<T: Real> DiffDrive<T> {
    /// Geometry with wheel radius `R` and track `L`, both > 0.
    pub fn new(wheel_radius: T, track: T) -> Result<Self, Error> {
        positive(wheel_radius, "wheel radius")?;
        positive(track, "track")?;
        Ok(Self {
            wheel_radius,
            track,
        })
    }

    /// The paper's robot: 10 cm wheels (`R` = 0.05 m), 60 cm track.
    pub fn paper() -> Self {
        Self {
            wheel_radius: T::lit(0.05),
            track: T::lit(0.60),
        }
    }

    /// Motion over one period (eqs. 1–2): `Δs_{L,R} = Δt·R·ω_{L,R}`,
    /// `Δs = (Δs_L + Δs_R)/2`, `Δθ = (Δs_R − Δs_L)/L`.
    pub fn motion(&self, w: &WheelSpeeds<T>) -> Motion<T> {
        let dsl = w.dt * self.wheel_radius * w.left;
        let dsr = w.dt * self.wheel_radius * w.right;
        Motion {
            ds: (dsl + dsr) * T::lit(0.5),
            dtheta: (dsr - dsl) / self.track,
        }
    }

    /// `J = ∂(Δs, e, Δθ)/∂(ω_R, ω_L) = [[ΔtR/2, ΔtR/2], [0, 0], [ΔtR/L, −ΔtR/L]]`: how
    /// wheel-speed errors move the motion step (`e` is the lateral displacement, which
    /// wheel speeds cannot cause).
    pub fn wheel_to_motion_jacobian(&self, dt: T) -> Matrix3x2<T> {
        let half = dt * self.wheel_radius * T::lit(0.5);
        let turn = dt * self.wheel_radius / self.track;
        Matrix3x2::new(half, half, T::zero(), T::zero(), turn, -turn)
    }

    /// The corrected input Jacobian `W = ∂f/∂(ω_R, ω_L)` of eq. 8 (docs/ERRATA.md 1:
    /// the third row is `(Δt·R/L, −Δt·R/L)`, twice the paper's printed value), computed as
    /// `W = G·J` ([`Motion::noise_jacobian`], [`DiffDrive::wheel_to_motion_jacobian`]).
    /// Columns are ordered `(ω_R, ω_L)` as in the paper's `Q = diag(δω_R², δω_L²)`.
    pub fn input_jacobian(&self, pose: &Pose2<T>, w: &WheelSpeeds<T>) -> Matrix3x2<T> {
        self.motion(w).noise_jacobian(pose) * self.wheel_to_motion_jacobian(w.dt)
    }
}

impl<T: Real> Motion<T> {
    /// A motion step `(Δs, Δθ)`. Fails on non-finite values.
    pub fn new(ds: T, dtheta: T) -> Result<Self, Error> {
        finite(ds, "motion ds")?;
        finite(dtheta, "motion dtheta")?;
        Ok(Self { ds, dtheta })
    }

    /// The motion between two consecutive odometry poses, for robots that publish only
    /// odometry: `Δθ = wrap(θ₂ − θ₁)`, and `Δs` the displacement projected on the
    /// mid-angle heading `θ₁ + Δθ/2` (its sign says forward or reverse). A lateral
    /// component of the displacement (wheel slip) is left to the lateral noise term.
    pub fn from_odometry_poses(from: &Pose2<T>, to: &Pose2<T>) -> Result<Self, Error> {
        from.validated("odometry pose")?;
        to.validated("odometry pose")?;
        let dtheta = crate::angle_diff(to.theta, from.theta);
        let mid = from.theta + dtheta * T::lit(0.5);
        let ds = (to.x - from.x) * mid.cos() + (to.y - from.y) * mid.sin();
        Ok(Self { ds, dtheta })
    }

    /// The motion model `f` (eq. 3): the pose advances `Δs` along the mid-angle
    /// `θ + Δθ/2`, then turns by `Δθ`.
    pub fn apply(&self, pose: &Pose2<T>) -> Pose2<T> {
        self.linearize(pose).next
    }

    /// The state Jacobian `A = ∂f/∂(x, y, θ)` (eq. 7).
    pub fn state_jacobian(&self, pose: &Pose2<T>) -> Matrix3<T> {
        self.linearize(pose).a
    }

    /// `G = ∂f/∂(Δs, e, Δθ)`: the Jacobian of the motion model with respect to the
    /// distance `Δs`, a lateral displacement `e` perpendicular to the mid-angle heading
    /// (zero in the nominal model), and the turn `Δθ`. Process noise in those three
    /// quantities maps into the state as `G Σ Gᵀ`.
    pub fn noise_jacobian(&self, pose: &Pose2<T>) -> Matrix3<T> {
        self.linearize(pose).g
    }

    /// `f`, `A` and `G` at `pose` together, with one sine and cosine of the mid-angle.
    pub fn linearize(&self, pose: &Pose2<T>) -> Linearization<T> {
        let (s, c) = (pose.theta + self.dtheta * T::lit(0.5)).sin_cos();
        let (o, i) = (T::zero(), T::one());
        let half = self.ds * T::lit(0.5);
        Linearization {
            next: Pose2::new(
                pose.x + self.ds * c,
                pose.y + self.ds * s,
                pose.theta + self.dtheta,
            ),
            a: Matrix3::new(i, o, -self.ds * s, o, i, self.ds * c, o, o, i),
            g: Matrix3::new(c, -s, -half * s, s, c, half * c, o, o, i),
        }
    }
}

/// The motion model and its Jacobians at one pose.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Linearization<T> {
    /// `f(x, u)`: the pose after the motion (eq. 3).
    pub next: Pose2<T>,
    /// `A = ∂f/∂(x, y, θ)` (eq. 7).
    pub a: Matrix3<T>,
    /// `G = ∂f/∂(Δs, e, Δθ)` (see [`Motion::noise_jacobian`]).
    pub g: Matrix3<T>,
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::f64::consts::{FRAC_PI_2, PI};

    #[test]
    fn straight_line_is_exact() {
        let robot = DiffDrive::<f64>::paper();
        let m = robot.motion(&WheelSpeeds::new(4.0, 4.0, 0.1).unwrap());
        assert_eq!(m.ds, 0.1 * 0.05 * 4.0);
        assert_eq!(m.dtheta, 0.0);
        let mut p = Pose2::new(1.0, 2.0, FRAC_PI_2);
        for _ in 0..50 {
            p = m.apply(&p);
        }
        assert!((p.x - 1.0).abs() < 1e-12);
        assert!((p.y - (2.0 + 50.0 * 0.02)).abs() < 1e-12);
        assert_eq!(p.theta, FRAC_PI_2);
    }

    #[test]
    fn pure_rotation_is_exact() {
        let robot = DiffDrive::<f64>::paper();
        // ω_R = −ω_L: Δs = 0, Δθ = 2·Δt·R·ω/L.
        let w = WheelSpeeds::new(-3.0, 3.0, 0.1).unwrap();
        let m = robot.motion(&w);
        assert_eq!(m.ds, 0.0);
        assert!((m.dtheta - 2.0 * 0.1 * 0.05 * 3.0 / 0.6).abs() < 1e-15);
        let mut p = Pose2::new(0.5, -0.5, 0.0);
        let n = 200;
        for _ in 0..n {
            p = m.apply(&p);
        }
        assert_eq!((p.x, p.y), (0.5, -0.5));
        assert!(crate::angle_diff(p.theta, n as f64 * 0.05).abs() < 1e-12);
        assert!(p.theta > -PI && p.theta <= PI);
    }

    #[test]
    fn increments_match_speeds() {
        let w = WheelSpeeds::from_increments(0.2_f64, 0.4, 0.1).unwrap();
        assert!((w.left - 2.0).abs() < 1e-15 && (w.right - 4.0).abs() < 1e-15);
        assert!(WheelSpeeds::new(f64::NAN, 0.0, 0.1).is_err());
        assert!(WheelSpeeds::new(0.0, 0.0, 0.0).is_err());
    }

    #[test]
    fn odometry_poses_round_trip() {
        let a = Pose2::new(1.0_f64, 1.0, 3.0);
        let m = Motion::new(0.3, 0.4).unwrap();
        let b = m.apply(&a);
        let back = Motion::from_odometry_poses(&a, &b).unwrap();
        assert!((back.ds - 0.3).abs() < 1e-12 && (back.dtheta - 0.4).abs() < 1e-12);
        let rev =
            Motion::from_odometry_poses(&a, &Motion::new(-0.2, 0.0).unwrap().apply(&a)).unwrap();
        assert!((rev.ds + 0.2).abs() < 1e-12);
    }
}
