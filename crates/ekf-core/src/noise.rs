//! Process-noise models: wheel-speed noise (paper eq. 9 plus a floor) and an
//! odometry-delta model in distance and rotation (AMCL's α parameters).

use crate::kinematics::{DiffDrive, Motion, WheelSpeeds};
use crate::validate::non_negative;
use crate::{Error, Real};
use nalgebra::{Matrix2, Matrix3};

/// Wheel-speed noise: `Q = diag(δ·ω_R² + σ₀², δ·ω_L² + σ₀²)` in (rad/s)².
///
/// The paper (eq. 9) uses `δ·ω²` alone (variance proportional to the squared speed). With
/// that alone a robot whose wheels barely turn gains no uncertainty at all, although its
/// encoders quantise and its wheels slip; the floor `σ₀²` models that. A 500-tick encoder
/// sampled every 0.1 s resolves ω to 2π/500/0.1 ≈ 0.126 rad/s, whose uniform quantisation
/// error has σ ≈ 0.036 rad/s: the default floor. A field missing when deserialized takes
/// the default's.
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
pub struct WheelNoise<T> {
    /// Proportional factor δ (dimensionless): variance `δ·ω²`. Paper: 0.01.
    pub delta: T,
    /// Variance floor σ₀² added to each wheel, (rad/s)².
    pub floor: T,
}

impl<T: Real> WheelNoise<T> {
    /// A wheel-noise model; both values must be finite and ≥ 0.
    pub fn new(delta: T, floor: T) -> Result<Self, Error> {
        non_negative(delta, "wheel noise delta")?;
        non_negative(floor, "wheel noise floor")?;
        Ok(Self { delta, floor })
    }

    /// The paper's value δ = 0.01, with no floor.
    pub fn paper() -> Self {
        Self {
            delta: T::lit(0.01),
            floor: T::zero(),
        }
    }

    /// `Q` of eq. 9 (plus floor), ordered `(ω_R, ω_L)`.
    pub fn input_covariance(&self, w: &WheelSpeeds<T>) -> Matrix2<T> {
        Matrix2::new(
            self.delta * w.right * w.right + self.floor,
            T::zero(),
            T::zero(),
            self.delta * w.left * w.left + self.floor,
        )
    }

    /// The noise of the motion step `(Δs, e, Δθ)`, `J Q Jᵀ` with `J` from
    /// [`DiffDrive::wheel_to_motion_jacobian`]; mapped into the state by `G`, this is the
    /// paper's `W Q Wᵀ` (eq. 6) with the corrected `W = G J`.
    pub fn motion_covariance(&self, robot: &DiffDrive<T>, w: &WheelSpeeds<T>) -> Matrix3<T> {
        let j = robot.wheel_to_motion_jacobian(w.dt);
        j * self.input_covariance(w) * j.transpose()
    }
}

impl<T: Real> Default for WheelNoise<T> {
    /// δ = 0.01 (the paper) and a floor of (0.036 rad/s)² (encoder quantisation).
    fn default() -> Self {
        Self {
            delta: T::lit(0.01),
            floor: T::lit(1.296e-3),
        }
    }
}

/// Noise of motion measured as odometry deltas, per step of translation `|Δs|` and
/// rotation `|Δθ|` (as AMCL's α parameters), as standard deviations:
///
/// - along the motion: `σ_s = a₁·|Δs| + b₁` (m)
/// - lateral (perpendicular to the mid-angle heading): `σ_e = a₂·|Δs| + b₂` (m)
/// - heading: `σ_θ = a₃·|Δθ| + a₄·|Δs| + b₃` (rad)
///
/// The constant terms `b` model what proportional terms miss (slip, timing). They apply
/// only to steps where the robot moved: a robot at rest with zero odometry delta gains no
/// uncertainty, however often its odometry is published. A field missing when
/// deserialized takes the default's.
///
/// A step is either one odometry message ([`motion_covariance`](Self::motion_covariance),
/// [`Ekf::predict_odometry`](crate::Ekf::predict_odometry)) or, as the localizer applies
/// it, the whole motion between two corrections, each message adding its share
/// ([`interval_covariance`](Self::interval_covariance), [`OdometryTravel`]), which
/// does not depend on the message rate.
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
pub struct OdometryNoise<T> {
    /// `a₁`: distance noise per metre travelled (m/m).
    pub a1: T,
    /// `b₁`: distance noise per step with motion (m).
    pub b1: T,
    /// `a₂`: lateral noise per metre travelled (m/m).
    pub a2: T,
    /// `b₂`: lateral noise per step with motion (m).
    pub b2: T,
    /// `a₃`: heading noise per radian turned (rad/rad).
    pub a3: T,
    /// `a₄`: heading noise per metre travelled (rad/m).
    pub a4: T,
    /// `b₃`: heading noise per step with motion (rad).
    pub b3: T,
}

impl<T: Real> OdometryNoise<T> {
    /// Fails unless every coefficient is finite and ≥ 0.
    pub fn validated(self) -> Result<Self, Error> {
        for (v, what) in [
            (self.a1, "odometry noise a1"),
            (self.b1, "odometry noise b1"),
            (self.a2, "odometry noise a2"),
            (self.b2, "odometry noise b2"),
            (self.a3, "odometry noise a3"),
            (self.a4, "odometry noise a4"),
            (self.b3, "odometry noise b3"),
        ] {
            non_negative(v, what)?;
        }
        Ok(self)
    }

    /// Standard deviations `(σ_s, σ_e, σ_θ)` for one motion step; all zero at rest.
    pub fn sigmas(&self, m: &Motion<T>) -> (T, T, T) {
        let (l, r) = (m.ds.abs(), m.dtheta.abs());
        if l == T::zero() && r == T::zero() {
            return (T::zero(), T::zero(), T::zero());
        }
        (
            self.a1 * l + self.b1,
            self.a2 * l + self.b2,
            self.a3 * r + self.a4 * l + self.b3,
        )
    }

    /// The noise of the motion step `(Δs, e, Δθ)`, `diag(σ_s², σ_e², σ_θ²)`; the filter maps
    /// it into the state with `G` from [`Motion::noise_jacobian`].
    pub fn motion_covariance(&self, m: &Motion<T>) -> Matrix3<T> {
        let (ss, se, st) = self.sigmas(m);
        Matrix3::from_diagonal(&nalgebra::Vector3::new(ss * ss, se * se, st * st))
    }

    /// The noise of the step `m` taken after `travel` within one noise interval, and
    /// `travel` advanced by it: the increment `σ²(L + |Δs|, R + |Δθ|) − σ²(L, R)` of each
    /// of the three variances of [`sigmas`](Self::sigmas), with `(L, R)` the distance and
    /// turn travelled in the interval so far (`σ² = 0` before any motion).
    ///
    /// Over an interval these increments add up to the variances of one step covering it,
    /// however many odometry messages it took: the noise is that of the motion between
    /// two corrections, not of the message rate (see [`OdometryTravel`]).
    pub fn interval_covariance(&self, travel: &mut OdometryTravel<T>, m: &Motion<T>) -> Matrix3<T> {
        let before = travel.sigmas(self);
        travel.distance += m.ds.abs();
        travel.turn += m.dtheta.abs();
        let after = travel.sigmas(self);
        let increment = |a: T, b: T| (a * a - b * b).max(T::zero());
        Matrix3::from_diagonal(&nalgebra::Vector3::new(
            increment(after.0, before.0),
            increment(after.1, before.1),
            increment(after.2, before.2),
        ))
    }
}

/// Distance and turn travelled since the filter was last corrected: the interval over
/// which [`OdometryNoise`] applies.
///
/// The model's proportional terms describe errors that persist over a stretch of motion
/// (a wheel radius or track width slightly off, a turn that slips the same way
/// throughout), and its constant terms one disturbance per stretch. Applied to every
/// odometry message as if each message's error were independent of the next, the same
/// metre of motion would get `n` times less variance from the proportional terms and `n`
/// times more from the constant ones when it arrives in `n` messages: 50 Hz odometry
/// would make the filter over-confident and 1 Hz odometry under-confident. Accumulated
/// over the interval between two corrections instead (as AMCL applies its model once per
/// filter update), the noise depends on the motion only.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OdometryTravel<T> {
    /// Distance travelled `Σ|Δs|` (m).
    pub distance: T,
    /// Turn `Σ|Δθ|` (rad).
    pub turn: T,
}

impl<T: Real> Default for OdometryTravel<T> {
    /// Nothing travelled: the start of an interval.
    fn default() -> Self {
        Self {
            distance: T::zero(),
            turn: T::zero(),
        }
    }
}

impl<T: Real> OdometryTravel<T> {
    /// Starts a new interval (after a correction).
    pub fn reset(&mut self) {
        *self = Self::default();
    }

    /// The model's standard deviations for the whole travel so far.
    fn sigmas(&self, noise: &OdometryNoise<T>) -> (T, T, T) {
        noise.sigmas(&Motion {
            ds: self.distance,
            dtheta: self.turn,
        })
    }
}

impl<T: Real> Default for OdometryNoise<T> {
    /// `σ_s = 0.05·L + 0.01 m`, `σ_e = 0.03·L + 0.01 m`,
    /// `σ_θ = 0.30·R + 0.07 rad/m·L + 0.5°`.
    ///
    /// The translation terms kept a prototype consistent on real indoor logs (ACES,
    /// Intel). The turn term covers the worst odometry of nine real robots (the CARMEN
    /// logs of `docs/RESULTS.md`): the heading error over a scan-to-scan turn, as a share
    /// of the turn, has an RMS of 0.01–0.12 on seven of them but 0.27 (csail) and 0.37
    /// (freiburg-campus) on the others. A default has to serve the robot it has not seen,
    /// and the two mistakes cost differently: odometry noisier than its model puts the
    /// truth outside the gates and loses the filter, while a model noisier than the
    /// odometry only lets the laser correct more (with joint-compatible association,
    /// ACES's RMSE is 0.070 m with 0.1 and with 0.3).
    fn default() -> Self {
        Self {
            a1: T::lit(0.05),
            b1: T::lit(0.01),
            a2: T::lit(0.03),
            b2: T::lit(0.01),
            a3: T::lit(0.30),
            a4: T::lit(0.07),
            b3: T::lit(0.5_f64.to_radians()),
        }
    }
}
