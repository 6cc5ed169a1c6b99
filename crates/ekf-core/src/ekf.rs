//! The extended Kalman filter: prediction (paper eqs. 5–9) and measurement update
//! (eqs. 10–12 in Joseph form) with chi-square gating.
//!
//! Names follow the textbook (and FilterPy): state `x`, covariance `P`, innovation `y`,
//! innovation covariance `S`, gain `K`. Measurements are fused one at a time, each with its
//! own gate; for independent measurement noise this equals the paper's stacked update
//! (eq. 16) up to relinearisation, and it lets a single bad line be rejected on its own.

use crate::kinematics::{DiffDrive, Motion, WheelSpeeds};
use crate::measurement::Measurement;
use crate::noise::{OdometryNoise, OdometryTravel, WheelNoise};
use crate::validate::{all_finite, covariance, finite, non_negative, semi_definite, spd_inverse};
use crate::{ChiSquareGate, Error, Pose2, Real};
use nalgebra::{Matrix3, SMatrix, SVector, Vector3};

/// Uncertain parameters `m` that a measurement depends on but the filter does not
/// estimate (a Schmidt–Kalman "consider" filter; Schmidt 1966, Simon 2006 §7.5), e.g. the
/// line `(ρ, β)` of a map wall that was itself measured. Their error is constant over
/// time, so it must not be averaged away as measurement noise would be.
///
/// With `h(x, m)` linearised as `H δx + H_m δm`, the innovation of
/// [`Ekf::update_considering`] has `Cov(δx, y) = P Hᵀ + X H_mᵀ` and
/// `S = H P Hᵀ + H X H_mᵀ + H_m Xᵀ Hᵀ + H_m C H_mᵀ + R`, where `X = Cov(δx, δm)` and
/// `C = Cov(δm)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Considered<T: Real, const M: usize, const N: usize> {
    /// `H_m = ∂h/∂m` at the current estimate (`M × N`).
    pub jacobian: SMatrix<T, M, N>,
    /// `X = Cov(δx, δm)`, the correlation of the state's error with the parameters'
    /// (`3 × N`).
    pub cross: SMatrix<T, 3, N>,
    /// `C = Cov(δm)` (`N × N`, symmetric positive semi-definite).
    pub covariance: SMatrix<T, N, N>,
}

impl<T: Real, const M: usize> Considered<T, M, 0> {
    /// No considered parameters: [`Ekf::update_considering`] with these is
    /// [`Ekf::update`], and also hands back the innovation and gain it used.
    pub fn none() -> Self {
        Self {
            jacobian: SMatrix::zeros(),
            cross: SMatrix::zeros(),
            covariance: SMatrix::zeros(),
        }
    }
}

/// What [`Ekf::update_considering`] did: the outcome, and the innovation and gain it
/// used, so that the caller can carry its cross-covariances with other parameters along
/// (see [`ConsideredUpdate::cross_after`]) and give them their share of the innovation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ConsideredUpdate<T: Real, const M: usize> {
    /// Whether the measurement was fused, its NIS and the error transition `I − K H`.
    pub outcome: UpdateOutcome<T>,
    /// The gain `K = (P Hᵀ + X H_mᵀ) S⁻¹` (zero if the measurement was rejected).
    pub gain: SMatrix<T, 3, M>,
    /// The innovation at the state before the update (what was fused, if it was).
    pub innovation: Innovation<T, M>,
}

impl<T: Real, const M: usize> ConsideredUpdate<T, M> {
    /// The state's cross-covariance with some parameters `k` after this update:
    /// `X_k⁺ = (I − K H) X_k − K H_m Cov(m, k)`, given `X_k = Cov(δx, δk)` before it and
    /// `h_m_cov = H_m Cov(δm, δk)` (`M × N`; zero when `k` is independent of the
    /// considered parameters `m`).
    pub fn cross_after<const N: usize>(
        &self,
        cross: &SMatrix<T, 3, N>,
        h_m_cov: &SMatrix<T, M, N>,
    ) -> SMatrix<T, 3, N> {
        self.outcome.transition * cross - self.gain * h_m_cov
    }
}

/// The filter state: pose estimate `x = [x, y, θ]` and its covariance `P`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ekf<T: Real> {
    x: Vector3<T>,
    p: Matrix3<T>,
}

/// An innovation, computed without changing the filter: `y = z − h(x)` (angles wrapped),
/// `S = H P Hᵀ + R` (plus the considered parameters' terms, see [`Considered`]), and
/// `NIS = yᵀ S⁻¹ y`.
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
    /// `X H_mᵀ`: the state error's correlation with the considered parameters' part of
    /// the innovation (zero without them).
    correlation: SMatrix<T, 3, M>,
    /// `H_m C H_mᵀ`: the considered parameters' part of `S` (zero without them).
    considered_noise: SMatrix<T, M, M>,
}

/// What an update did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UpdateOutcome<T: Real> {
    /// `true` if the measurement passed the gate and was fused; `false` if it was
    /// rejected and the state is unchanged.
    pub accepted: bool,
    /// Its normalised innovation squared.
    pub nis: T,
    /// `I − K H`, which maps the state's error before the update onto its error after it
    /// (the identity if the measurement was rejected). A cross-covariance `Cov(δx, δk)`
    /// of the state with anything the measurement's noise and considered parameters are
    /// independent of becomes `(I − K H) Cov(δx, δk)`; otherwise see
    /// [`ConsideredUpdate::cross_after`].
    pub transition: Matrix3<T>,
}

impl<T: Real, const M: usize> Innovation<T, M> {
    /// `S⁻¹`: the gain of anything correlated with the innovation is `Cov(·, y) S⁻¹`.
    pub fn s_inverse(&self) -> &SMatrix<T, M, M> {
        &self.s_inv
    }
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
    ///
    /// Every prediction returns the transition Jacobian `A` it used: a cross-covariance
    /// `Cov(δx, δm)` of the state with parameters the motion does not change becomes
    /// `A Cov(δx, δm)`.
    pub fn predict(
        &mut self,
        motion: &Motion<T>,
        motion_covariance: &Matrix3<T>,
    ) -> Result<Matrix3<T>, Error> {
        finite(motion.ds, "motion ds")?;
        finite(motion.dtheta, "motion dtheta")?;
        semi_definite(motion_covariance, "motion noise")?;
        Ok(self.propagate(motion, motion_covariance))
    }

    /// Adds process noise `Q` (symmetric positive semi-definite) to `P` without moving the
    /// state: a disturbance the motion model does not describe (a wheel slip, a bump).
    /// Noise independent of everything else leaves cross-covariances with other
    /// parameters unchanged (`A = I`); a caller whose parameters share the disturbance
    /// adds its part to them itself. Fails, leaving the filter as it was, if `Q` is not
    /// finite, not symmetric or not positive semi-definite.
    pub fn add_process_noise(&mut self, q: &Matrix3<T>) -> Result<(), Error> {
        semi_definite(q, "process noise")?;
        self.p = symmetrize(&(self.p + q));
        Ok(())
    }

    /// Eqs. 5–6 for a motion and a motion covariance already checked (finite, and
    /// positive semi-definite by construction from validated noise parameters); returns
    /// `A`.
    fn propagate(&mut self, motion: &Motion<T>, motion_covariance: &Matrix3<T>) -> Matrix3<T> {
        let lin = motion.linearize(&self.pose());
        let p = lin.a * self.p * lin.a.transpose() + lin.g * motion_covariance * lin.g.transpose();
        self.x = lin.next.to_vector();
        self.p = symmetrize(&p);
        lin.a
    }

    /// Prediction from wheel speeds (eqs. 1–9): motion from the kinematics, noise
    /// `W Q Wᵀ` with the corrected `W` and `Q = diag(δω_R² + σ₀², δω_L² + σ₀²)`. Returns
    /// `A` (see [`Ekf::predict`]).
    pub fn predict_wheels(
        &mut self,
        robot: &DiffDrive<T>,
        speeds: &WheelSpeeds<T>,
        noise: &WheelNoise<T>,
    ) -> Result<Matrix3<T>, Error> {
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
        Ok(self.propagate(&motion, &sigma))
    }

    /// Prediction from an odometry delta `(Δs, Δθ)` with the distance/rotation noise
    /// model, the step its own noise interval (the noise is
    /// [`OdometryNoise::motion_covariance`]). Returns `A` (see [`Ekf::predict`]).
    pub fn predict_odometry(
        &mut self,
        motion: &Motion<T>,
        noise: &OdometryNoise<T>,
    ) -> Result<Matrix3<T>, Error> {
        self.predict_odometry_in(motion, noise, &mut OdometryTravel::default())
    }

    /// Prediction from an odometry delta `(Δs, Δθ)` taken after `travel` within the
    /// current noise interval: the noise is the step's share of the interval's
    /// ([`OdometryNoise::interval_covariance`]), and `travel` advances. Returns `A` (see
    /// [`Ekf::predict`]).
    pub fn predict_odometry_in(
        &mut self,
        motion: &Motion<T>,
        noise: &OdometryNoise<T>,
        travel: &mut OdometryTravel<T>,
    ) -> Result<Matrix3<T>, Error> {
        finite(motion.ds, "motion ds")?;
        finite(motion.dtheta, "motion dtheta")?;
        noise.validated()?;
        let mut advanced = *travel;
        // Increments of variances that grow with the travel: positive semi-definite.
        let sigma = noise.interval_covariance(&mut advanced, motion);
        all_finite(sigma.as_slice(), "motion noise")?;
        *travel = advanced;
        Ok(self.propagate(motion, &sigma))
    }

    /// The innovation of a measurement at the current estimate, without changing the
    /// filter. Fails if the measurement or its noise is invalid.
    // Inlined so that each update stays one function, as `update` was before
    // `update_reporting` shared its parts (left to LLVM, ekf_loc's batch step took ~10 % longer).
    #[inline(always)]
    pub fn innovation<const M: usize, Z: Measurement<T, M>>(
        &self,
        m: &Z,
    ) -> Result<Innovation<T, M>, Error> {
        self.innovation_with(m, SMatrix::zeros(), SMatrix::zeros())
    }

    /// The innovation of a measurement that also depends on `considered` parameters (see
    /// [`Considered`]), without changing the filter. Fails if the measurement, its noise
    /// or the parameters' covariances are invalid.
    pub fn innovation_considering<const M: usize, const N: usize, Z: Measurement<T, M>>(
        &self,
        m: &Z,
        considered: &Considered<T, M, N>,
    ) -> Result<Innovation<T, M>, Error> {
        all_finite(
            considered.jacobian.as_slice(),
            "considered parameters' Jacobian",
        )?;
        all_finite(considered.cross.as_slice(), "considered cross-covariance")?;
        semi_definite(&considered.covariance, "considered parameters' covariance")?;
        let h_m = &considered.jacobian;
        self.innovation_with(
            m,
            considered.cross * h_m.transpose(),
            h_m * considered.covariance * h_m.transpose(),
        )
    }

    /// The innovation with the considered parameters' terms `X H_mᵀ` and `H_m C H_mᵀ`.
    // Inlined: see `innovation`.
    #[inline(always)]
    fn innovation_with<const M: usize, Z: Measurement<T, M>>(
        &self,
        m: &Z,
        correlation: SMatrix<T, 3, M>,
        considered_noise: SMatrix<T, M, M>,
    ) -> Result<Innovation<T, M>, Error> {
        let z = m.measured();
        all_finite(z.as_slice(), "measurement")?;
        let r = m.noise();
        covariance(&r, "measurement noise")?;
        let (z_hat, h) = m.predict(&self.pose());
        let y = m.residual(&z, &z_hat);
        all_finite(y.as_slice(), "innovation")?;
        let h_corr = h * correlation;
        let s = symmetrize(
            &(h * self.p * h.transpose() + h_corr + h_corr.transpose() + considered_noise + r),
        );
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
            correlation,
            considered_noise,
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
        check_gate::<T, M>(gate)?;
        let innovation = self.innovation(m)?;
        Ok(self.fuse_gated(&innovation, gate)?.0)
    }

    /// [`Ekf::update`] that also hands back what it computed, named as in FilterPy: the
    /// innovation `y = z − h(x)` (angles wrapped) and its covariance `S = H P Hᵀ + R`, both
    /// at the state before the update, in [`ConsideredUpdate::innovation`], and the gain
    /// `K = P Hᵀ S⁻¹` of eq. 10 in [`ConsideredUpdate::gain`] — the gain applied, so zero
    /// if the gate refused the measurement (`y` and `S` are those it was refused on). The
    /// state, covariance and outcome are those of [`Ekf::update`] bit for bit (and of
    /// [`Ekf::update_considering`] with [`Considered::none`], without that call's checks of
    /// the empty considered parameters). No allocation: everything is fixed-size.
    pub fn update_reporting<const M: usize, Z: Measurement<T, M>>(
        &mut self,
        m: &Z,
        gate: Option<&ChiSquareGate<T>>,
    ) -> Result<ConsideredUpdate<T, M>, Error> {
        check_gate::<T, M>(gate)?;
        let innovation = self.innovation(m)?;
        let (outcome, gain) = self.fuse_gated(&innovation, gate)?;
        Ok(ConsideredUpdate {
            outcome,
            gain,
            innovation,
        })
    }

    /// Schmidt–Kalman update of a measurement that also depends on `considered`
    /// parameters (see [`Considered`]): the parameters keep their estimate and covariance,
    /// and the state is updated with `K = (P Hᵀ + X H_mᵀ) S⁻¹`, `x = x⁻ + K y` and, in the
    /// Joseph form that holds for any gain,
    /// `P = (I − K H) P⁻ (I − K H)ᵀ − (I − K H) X H_mᵀ Kᵀ − K H_m Xᵀ (I − K H)ᵀ
    /// + K (H_m C H_mᵀ + R) Kᵀ`, symmetrised. This is the state block of the Kalman update
    /// of the state augmented with the parameters. With a zero `X` and `C` it equals
    /// [`Ekf::update`]. Gating as there.
    pub fn update_considering<const M: usize, const N: usize, Z: Measurement<T, M>>(
        &mut self,
        m: &Z,
        considered: &Considered<T, M, N>,
        gate: Option<&ChiSquareGate<T>>,
    ) -> Result<ConsideredUpdate<T, M>, Error> {
        check_gate::<T, M>(gate)?;
        let innovation = self.innovation_considering(m, considered)?;
        let (outcome, gain) = self.fuse_gated(&innovation, gate)?;
        Ok(ConsideredUpdate {
            outcome,
            gain,
            innovation,
        })
    }

    /// Fuses `inn` if it passes `gate`; returns the outcome and the gain used (zero if
    /// rejected).
    // Inlined: see `innovation`.
    #[inline(always)]
    fn fuse_gated<const M: usize>(
        &mut self,
        inn: &Innovation<T, M>,
        gate: Option<&ChiSquareGate<T>>,
    ) -> Result<(UpdateOutcome<T>, SMatrix<T, 3, M>), Error> {
        let accepted = gate.is_none_or(|g| g.accepts(inn.nis));
        let (transition, gain) = if accepted {
            self.apply(inn)?
        } else {
            (Matrix3::identity(), SMatrix::zeros())
        };
        let outcome = UpdateOutcome {
            accepted,
            nis: inn.nis,
            transition,
        };
        Ok((outcome, gain))
    }

    /// Fuses an innovation computed at the current state (private: an innovation from an
    /// earlier state would be fused silently wrong; [`Ekf::update`] recomputes it).
    /// Returns `I − K H` and `K`.
    // Inlined: see `innovation`.
    #[inline(always)]
    fn apply<const M: usize>(
        &mut self,
        inn: &Innovation<T, M>,
    ) -> Result<(Matrix3<T>, SMatrix<T, 3, M>), Error> {
        let k = (self.p * inn.h.transpose() + inn.correlation) * inn.s_inv;
        let x = self.x + k * inn.y;
        let i_kh = Matrix3::identity() - k * inn.h;
        let cross = i_kh * inn.correlation * k.transpose();
        let p = i_kh * self.p * i_kh.transpose() - cross - cross.transpose()
            + k * (inn.considered_noise + inn.r) * k.transpose();
        let p = symmetrize(&p);
        all_finite(x.as_slice(), "updated state")?;
        all_finite(p.as_slice(), "updated covariance")?;
        self.x = Pose2::from_vector(&x).to_vector();
        self.p = p;
        Ok((i_kh, k))
    }
}

/// Fails unless a gate's degrees of freedom equal the measurement's dimension `M`.
fn check_gate<T: Real, const M: usize>(gate: Option<&ChiSquareGate<T>>) -> Result<(), Error> {
    match gate {
        Some(g) if g.dof as usize != M => Err(Error::OutOfRange {
            what: "gate degrees of freedom",
            expected: "equal to the measurement dimension",
        }),
        _ => Ok(()),
    }
}

/// `(M + Mᵀ)/2`: removes the round-off asymmetry the products accumulate.
fn symmetrize<T: Real, const N: usize>(m: &SMatrix<T, N, N>) -> SMatrix<T, N, N> {
    (m + m.transpose()) * T::lit(0.5)
}
