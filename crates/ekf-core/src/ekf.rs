//! The extended Kalman filter: prediction (paper eqs. 5–9) and measurement update
//! (eqs. 10–12 in Joseph form) with chi-square gating.
//!
//! Names follow the textbook (and FilterPy): state `x`, covariance `P`, innovation `y`,
//! innovation covariance `S`, gain `K`. Measurements are fused one at a time, each with its
//! own gate; for independent measurement noise this equals the paper's stacked update
//! (eq. 16) up to relinearisation, and it lets a single bad line be rejected on its own.

use crate::kinematics::{DiffDrive, Motion, WheelSpeeds};
use crate::measurement::Measurement;
use crate::noise::{OdometryNoise, WheelNoise};
use crate::validate::{all_finite, covariance, finite, non_negative, semi_definite, spd_inverse};
use crate::{ChiSquareGate, Error, Pose2, Real};
use nalgebra::{Matrix3, SMatrix, SVector, Vector3};

/// The filter state: pose estimate `x = [x, y, θ]` and its covariance `P`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ekf<T: Real> {
    x: Vector3<T>,
    p: Matrix3<T>,
}

/// An innovation, computed without changing the filter: `y = z − h(x)` (angles wrapped),
/// `S = H P Hᵀ + R`, and `NIS = yᵀ S⁻¹ y`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Innovation<T: Real, const M: usize> {
    /// The innovation `y`.
    pub y: SVector<T, M>,
    /// Its covariance `S`.
    pub s: SMatrix<T, M, M>,
    /// The measurement Jacobian `H` at the current estimate.
    pub h: SMatrix<T, M, 3>,
    /// The measurement noise `R`.
    pub r: SMatrix<T, M, M>,
    /// Normalised innovation squared `yᵀ S⁻¹ y`, chi-square with `M` dof when consistent.
    pub nis: T,
    /// `S⁻¹`, reused by the gain.
    s_inv: SMatrix<T, M, M>,
}

/// What an update did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UpdateOutcome<T> {
    /// `true` if the measurement passed the gate and was fused; `false` if it was
    /// rejected and the state is unchanged.
    pub accepted: bool,
    /// Its normalised innovation squared.
    pub nis: T,
}

impl<T: Real> Ekf<T> {
    /// A filter at `pose` with covariance `P`. Fails unless the pose is finite and `P` is
    /// symmetric positive definite.
    pub fn new(pose: Pose2<T>, p: Matrix3<T>) -> Result<Self, Error> {
        pose.validated("initial pose")?;
        covariance(&p, "initial covariance")?;
        Ok(Self {
            x: pose.to_vector(),
            p,
        })
    }

    /// The pose estimate (θ wrapped).
    pub fn pose(&self) -> Pose2<T> {
        Pose2::from_vector(&self.x)
    }

    /// The state vector `[x, y, θ]`.
    pub fn state(&self) -> &Vector3<T> {
        &self.x
    }

    /// The covariance `P`, symmetric positive definite.
    pub fn covariance(&self) -> &Matrix3<T> {
        &self.p
    }

    /// Generic prediction (eqs. 5–6): `x⁻ = f(x, u)`, `P⁻ = A P Aᵀ + G Σ Gᵀ`, where `Σ` is
    /// the covariance of the motion step in `(Δs, e, Δθ)` (distance, lateral displacement,
    /// turn) and `G` = [`Motion::noise_jacobian`]. For wheel noise `Σ = J Q Jᵀ` and
    /// `G Σ Gᵀ = W Q Wᵀ` exactly.
    pub fn predict(
        &mut self,
        motion: &Motion<T>,
        motion_covariance: &Matrix3<T>,
    ) -> Result<(), Error> {
        finite(motion.ds, "motion ds")?;
        finite(motion.dtheta, "motion dtheta")?;
        semi_definite(motion_covariance, "motion noise")?;
        self.propagate(motion, motion_covariance);
        Ok(())
    }

    /// Eqs. 5–6 for a motion and a motion covariance already checked (finite, and
    /// positive semi-definite by construction from validated noise parameters).
    fn propagate(&mut self, motion: &Motion<T>, motion_covariance: &Matrix3<T>) {
        let lin = motion.linearize(&self.pose());
        let p = lin.a * self.p * lin.a.transpose() + lin.g * motion_covariance * lin.g.transpose();
        self.x = lin.next.to_vector();
        self.p = symmetrize(&p);
    }

    /// Prediction from wheel speeds (eqs. 1–9): motion from the kinematics, noise
    /// `W Q Wᵀ` with the corrected `W` and `Q = diag(δω_R² + σ₀², δω_L² + σ₀²)`.
    pub fn predict_wheels(
        &mut self,
        robot: &DiffDrive<T>,
        speeds: &WheelSpeeds<T>,
        noise: &WheelNoise<T>,
    ) -> Result<(), Error> {
        finite(speeds.left, "left wheel speed")?;
        finite(speeds.right, "right wheel speed")?;
        finite(speeds.dt, "dt")?;
        non_negative(noise.delta, "wheel noise delta")?;
        non_negative(noise.floor, "wheel noise floor")?;
        let motion = robot.motion(speeds);
        finite(motion.ds, "motion ds")?;
        finite(motion.dtheta, "motion dtheta")?;
        // J Q Jᵀ with Q = diag(δω² + σ₀²) ≥ 0 is positive semi-definite by construction.
        let sigma = noise.motion_covariance(robot, speeds);
        all_finite(sigma.as_slice(), "motion noise")?;
        self.propagate(&motion, &sigma);
        Ok(())
    }

    /// Prediction from an odometry delta `(Δs, Δθ)` with the distance/rotation noise
    /// model.
    pub fn predict_odometry(
        &mut self,
        motion: &Motion<T>,
        noise: &OdometryNoise<T>,
    ) -> Result<(), Error> {
        finite(motion.ds, "motion ds")?;
        finite(motion.dtheta, "motion dtheta")?;
        noise.validated()?;
        // diag(σ_s², σ_e², σ_θ²) is positive semi-definite by construction.
        let sigma = noise.motion_covariance(motion);
        all_finite(sigma.as_slice(), "motion noise")?;
        self.propagate(motion, &sigma);
        Ok(())
    }

    /// The innovation of a measurement at the current estimate, without changing the
    /// filter. Fails if the measurement or its noise is invalid.
    pub fn innovation<const M: usize, Z: Measurement<T, M>>(
        &self,
        m: &Z,
    ) -> Result<Innovation<T, M>, Error> {
        let z = m.measured();
        all_finite(z.as_slice(), "measurement")?;
        let r = m.noise();
        covariance(&r, "measurement noise")?;
        let (z_hat, h) = m.predict(&self.pose());
        let y = m.residual(&z, &z_hat);
        all_finite(y.as_slice(), "innovation")?;
        let s = symmetrize(&(h * self.p * h.transpose() + r));
        let s_inv = spd_inverse(&s).ok_or(Error::NotPositiveDefinite {
            what: "innovation covariance",
        })?;
        let nis = (y.transpose() * s_inv * y)[(0, 0)];
        Ok(Innovation {
            y,
            s,
            h,
            r,
            nis,
            s_inv,
        })
    }

    /// Measurement update (eqs. 10–12): `K = P Hᵀ S⁻¹`, `x = x⁻ + K y`, and `P` in Joseph
    /// form `(I − K H) P⁻ (I − K H)ᵀ + K R Kᵀ`, symmetrised. With a `gate`, a measurement
    /// whose NIS exceeds the threshold is rejected and the state left unchanged; the gate's
    /// degrees of freedom must equal the measurement's dimension `M`.
    pub fn update<const M: usize, Z: Measurement<T, M>>(
        &mut self,
        m: &Z,
        gate: Option<&ChiSquareGate<T>>,
    ) -> Result<UpdateOutcome<T>, Error> {
        if let Some(g) = gate {
            if g.dof as usize != M {
                return Err(Error::OutOfRange {
                    what: "gate degrees of freedom",
                    expected: "equal to the measurement dimension",
                });
            }
        }
        let innovation = self.innovation(m)?;
        let accepted = gate.is_none_or(|g| g.accepts(innovation.nis));
        if accepted {
            self.apply(&innovation)?;
        }
        Ok(UpdateOutcome {
            accepted,
            nis: innovation.nis,
        })
    }

    /// Fuses an innovation computed at the current state (private: an innovation from an
    /// earlier state would be fused silently wrong; [`Ekf::update`] recomputes it).
    fn apply<const M: usize>(&mut self, inn: &Innovation<T, M>) -> Result<(), Error> {
        let k = self.p * inn.h.transpose() * inn.s_inv;
        let x = self.x + k * inn.y;
        let i_kh = Matrix3::identity() - k * inn.h;
        let p = symmetrize(&(i_kh * self.p * i_kh.transpose() + k * inn.r * k.transpose()));
        all_finite(x.as_slice(), "updated state")?;
        all_finite(p.as_slice(), "updated covariance")?;
        self.x = Pose2::from_vector(&x).to_vector();
        self.p = p;
        Ok(())
    }
}

/// `(M + Mᵀ)/2`: removes the round-off asymmetry the products accumulate.
fn symmetrize<T: Real, const N: usize>(m: &SMatrix<T, N, N>) -> SMatrix<T, N, N> {
    (m + m.transpose()) * T::lit(0.5)
}
