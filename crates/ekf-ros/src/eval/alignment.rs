//! Aligning an estimate to the reference before computing errors: Umeyama's least-squares
//! similarity in the plane, and `evo`'s origin alignment.

use super::{EvalError, Matched};
use crate::trajectory::{StampedPose, Trajectory};
use ekf_core::Pose2;
use nalgebra::Point2;
use serde::Serialize;

/// Which alignment to apply to the estimate (`evo`'s `-a`, `-s`, `--align_origin`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum AlignMode {
    /// No alignment (`evo`'s default).
    #[default]
    None,
    /// Rotation and translation by Umeyama's method (`evo -a`, SE(3) there, SE(2) here).
    Rigid,
    /// Rotation, translation and scale by Umeyama's method (`evo -a -s`).
    RigidAndScale,
    /// Only the Umeyama scale, applied about the origin (`evo -s` without `-a`).
    ScaleOnly,
    /// Move the estimate's first pose onto the reference's first pose
    /// (`evo --align_origin`).
    Origin,
}

/// How the estimate is aligned to the reference.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct AlignmentOptions {
    /// The kind of alignment.
    pub mode: AlignMode,
    /// Use only the first `n` matched poses to compute an Umeyama alignment
    /// (`evo --n_to_align`); `None` uses all. Ignored by [`AlignMode::Origin`].
    pub n_to_align: Option<usize>,
}

/// A planar similarity `p ↦ s·R(φ)·p + t`, applied to a pose as
/// `(x, y, θ) ↦ (s·R(φ)·(x, y) + t, θ + φ)`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Alignment {
    /// Rotation angle φ (rad).
    pub rotation_rad: f64,
    /// Translation `t = (t_x, t_y)` (m).
    pub translation: [f64; 2],
    /// Scale `s` (1 unless a scale was estimated).
    pub scale: f64,
}

impl Alignment {
    /// The identity transform.
    pub fn identity() -> Self {
        Self {
            rotation_rad: 0.0,
            translation: [0.0, 0.0],
            scale: 1.0,
        }
    }

    /// The transform applied to a pose: `(s·R(φ)·(x, y) + t, θ + φ)` (θ wrapped).
    pub fn apply(&self, pose: &Pose2<f64>) -> Pose2<f64> {
        let (sin, cos) = self.rotation_rad.sin_cos();
        let (x, y) = (self.scale * pose.x, self.scale * pose.y);
        Pose2::new(
            cos * x - sin * y + self.translation[0],
            sin * x + cos * y + self.translation[1],
            pose.theta + self.rotation_rad,
        )
    }
}

/// Umeyama's least-squares alignment of `estimate` points onto `reference` points (pairs
/// by index), in the plane: the `s`, `φ`, `t` minimising `Σ |r_k − (s·R(φ)·e_k + t)|²`.
///
/// With the centred points `a_k = e_k − ē`, `b_k = r_k − r̄`, the sums
/// `C = Σ a_k·b_k` and `S = Σ a_k × b_k = Σ (a_x b_y − a_y b_x)` give the closed form
///
/// `φ = atan2(S, C)`,  `s = √(C² + S²) / Σ |a_k|²` (or 1 when `with_scale` is false),
/// `t = r̄ − s·R(φ)·ē`.
///
/// This is Umeyama's SVD solution restricted to proper rotations, and equals `evo`'s
/// SE(3)/Sim(3) alignment of the same points with `z = 0`, except in two corner cases:
/// if the best planar fit is a mirror image (`det Σ_xy < 0`), `evo` may turn the
/// estimate upside down (a 180° rotation about an in-plane axis) where this keeps a
/// rotation about z; and `evo` refuses collinear estimates (rank-1 covariance) which have
/// a unique planar rotation here. Fails with [`EvalError::DegenerateAlignment`] if the
/// inputs are empty, of different lengths, or `√(C² + S²)/n` is below machine epsilon
/// (no rotation is defined).
pub fn umeyama(
    estimate: &[Point2<f64>],
    reference: &[Point2<f64>],
    with_scale: bool,
) -> Result<Alignment, EvalError> {
    let n = estimate.len();
    let degenerate = EvalError::DegenerateAlignment { poses: n };
    if n == 0 || reference.len() != n {
        return Err(degenerate);
    }
    let mean = |points: &[Point2<f64>]| {
        let sum = points
            .iter()
            .fold([0.0, 0.0], |acc, p| [acc[0] + p.x, acc[1] + p.y]);
        [sum[0] / n as f64, sum[1] / n as f64]
    };
    let (e_mean, r_mean) = (mean(estimate), mean(reference));
    let (mut c, mut s, mut var) = (0.0, 0.0, 0.0);
    for (e, r) in estimate.iter().zip(reference) {
        let a = [e.x - e_mean[0], e.y - e_mean[1]];
        let b = [r.x - r_mean[0], r.y - r_mean[1]];
        c += a[0] * b[0] + a[1] * b[1];
        s += a[0] * b[1] - a[1] * b[0];
        var += a[0] * a[0] + a[1] * a[1];
    }
    let norm = c.hypot(s);
    if norm / n as f64 <= f64::EPSILON {
        return Err(degenerate);
    }
    let rotation_rad = s.atan2(c);
    let scale = if with_scale { norm / var } else { 1.0 };
    let (sin, cos) = rotation_rad.sin_cos();
    let translation = [
        r_mean[0] - scale * (cos * e_mean[0] - sin * e_mean[1]),
        r_mean[1] - scale * (sin * e_mean[0] + cos * e_mean[1]),
    ];
    Ok(Alignment {
        rotation_rad,
        translation,
        scale,
    })
}

/// The matched estimate aligned to the matched reference as `options` asks, and the
/// transform used (`None` for [`AlignMode::None`]).
///
/// [`AlignMode::Origin`] uses `T = ref_0 ⊕ est_0⁻¹`, so the first estimated pose lands on
/// the first reference pose.
pub fn align_estimate(
    matched: &Matched,
    options: &AlignmentOptions,
) -> Result<(Trajectory, Option<Alignment>), EvalError> {
    let alignment = match options.mode {
        AlignMode::None => return Ok((matched.estimate.clone(), None)),
        AlignMode::Origin => origin_alignment(matched)?,
        AlignMode::Rigid | AlignMode::RigidAndScale | AlignMode::ScaleOnly => {
            let n = options
                .n_to_align
                .map_or(matched.len(), |n| n.min(matched.len()));
            let points = |t: &Trajectory| -> Vec<Point2<f64>> {
                t.iter()
                    .take(n)
                    .map(|s| Point2::new(s.pose.x, s.pose.y))
                    .collect()
            };
            let with_scale = options.mode != AlignMode::Rigid;
            let fit = umeyama(
                &points(&matched.estimate),
                &points(&matched.reference),
                with_scale,
            )?;
            if options.mode == AlignMode::ScaleOnly {
                Alignment {
                    scale: fit.scale,
                    ..Alignment::identity()
                }
            } else {
                fit
            }
        }
    };
    let aligned = matched
        .estimate
        .iter()
        .map(|s| StampedPose::new(s.t_ns, alignment.apply(&s.pose)))
        .collect();
    Ok((aligned, Some(alignment)))
}

/// `T = ref_0 ⊕ est_0⁻¹` as an [`Alignment`].
fn origin_alignment(matched: &Matched) -> Result<Alignment, EvalError> {
    let (Some(reference), Some(estimate)) = (
        matched.reference.samples.first(),
        matched.estimate.samples.first(),
    ) else {
        return Err(EvalError::DegenerateAlignment { poses: 0 });
    };
    let t = reference.pose.compose(&estimate.pose.inverse());
    Ok(Alignment {
        rotation_rad: t.theta,
        translation: [t.x, t.y],
        scale: 1.0,
    })
}
