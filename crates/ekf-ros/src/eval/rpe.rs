//! Relative pose error (RPE): how much the estimated motion between two poses differs
//! from the reference motion, as `evo_rpe` computes it (step in frames).

use super::{
    align_estimate, associate, Alignment, AlignmentOptions, AssociationOptions, EvalError,
    Statistics,
};
use crate::trajectory::Trajectory;
use serde::Serialize;

/// Options of [`rpe`] (`evo_rpe`'s defaults: 10 ms, no alignment, `delta = 1` frame,
/// consecutive pairs).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RpeOptions {
    /// How poses are paired in time.
    pub association: AssociationOptions,
    /// How the estimate is aligned first (a rigid alignment does not change the RPE;
    /// a scale does).
    pub alignment: AlignmentOptions,
    /// Step `Δ` between the two poses of a pair, in matched frames (`evo --delta`,
    /// `--delta_unit f`). At least 1.
    pub delta_frames: usize,
    /// `false`: pairs `(0, Δ), (Δ, 2Δ), …`; `true`: every `(i, i + Δ)`
    /// (`evo --all_pairs`). The same for `Δ = 1`.
    pub all_pairs: bool,
}

impl Default for RpeOptions {
    fn default() -> Self {
        Self {
            association: AssociationOptions::default(),
            alignment: AlignmentOptions::default(),
            delta_frames: 1,
            all_pairs: false,
        }
    }
}

/// The relative error of one pose pair `(i, j)`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct RelativeError {
    /// Index of the first pose among the matched poses.
    pub i: usize,
    /// Index of the second pose among the matched poses.
    pub j: usize,
    /// Stamp of the second reference pose (ns), as `evo` plots it.
    pub t_ns: u64,
    /// Translation norm of `E_ij` (m).
    pub translation: f64,
    /// Rotation angle of `E_ij`, `|θ(E_ij)|` in [0°, 180°] (degrees).
    pub heading_deg: f64,
}

/// What `evo_rpe` reports, for a planar trajectory. Serializes to JSON.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RpeSummary {
    /// Poses in the reference file.
    pub reference_poses: usize,
    /// Poses in the estimate file.
    pub estimate_poses: usize,
    /// Poses paired by time stamp.
    pub matched_poses: usize,
    /// Pose pairs `(i, j)` the statistics are over.
    pub pairs: usize,
    /// The step `Δ` (frames).
    pub delta_frames: usize,
    /// Whether all pairs `(i, i + Δ)` were used.
    pub all_pairs: bool,
    /// The alignment applied to the estimate, if any.
    pub alignment: Option<Alignment>,
    /// Statistics of `|trans(E_ij)|` (m): `evo_rpe -r trans_part` (the default).
    pub translation_m: Statistics,
    /// Statistics of `|θ(E_ij)|` (degrees): `evo_rpe -r angle_deg`.
    pub heading_error_deg: Statistics,
}

/// The RPE: its summary and the error of every pair (for plots).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Rpe {
    /// Statistics and counts.
    pub summary: RpeSummary,
    /// One error per pair, in order of `i`.
    pub errors: Vec<RelativeError>,
}

/// The relative pose error of `estimate` against `reference`.
///
/// After pairing and optional alignment (as [`super::ape`]), for each index pair
/// `(i, j = i + Δ)` of matched poses with reference poses `Q` and estimated poses `P`:
///
/// `E_ij = (Q_i⁻¹ ⊕ Q_j)⁻¹ ⊕ (P_i⁻¹ ⊕ P_j)`,
///
/// whose translation norm and absolute rotation angle are the errors (TUM RGB-D
/// benchmark definition, as `evo`'s `rpe_base`).
pub fn rpe(
    reference: &Trajectory,
    estimate: &Trajectory,
    options: &RpeOptions,
) -> Result<Rpe, EvalError> {
    let delta = options.delta_frames;
    if delta == 0 {
        return Err(EvalError::InvalidDelta { delta });
    }
    let matched = associate(reference, estimate, &options.association)?;
    let (aligned, alignment) = align_estimate(&matched, &options.alignment)?;
    let step = if options.all_pairs { 1 } else { delta };
    let (q, p) = (&matched.reference.samples, &aligned.samples);
    let errors: Vec<RelativeError> = (0..matched.len().saturating_sub(delta))
        .step_by(step)
        .map(|i| {
            let j = i + delta;
            let q_rel = q[i].pose.inverse().compose(&q[j].pose);
            let p_rel = p[i].pose.inverse().compose(&p[j].pose);
            let e = q_rel.inverse().compose(&p_rel);
            RelativeError {
                i,
                j,
                t_ns: q[j].t_ns,
                translation: e.x.hypot(e.y),
                heading_deg: e.theta.abs().to_degrees(),
            }
        })
        .collect();
    if errors.is_empty() {
        return Err(EvalError::NoPairs {
            delta,
            poses: matched.len(),
        });
    }
    let translation: Vec<f64> = errors.iter().map(|e| e.translation).collect();
    let heading: Vec<f64> = errors.iter().map(|e| e.heading_deg).collect();
    Ok(Rpe {
        summary: RpeSummary {
            reference_poses: reference.len(),
            estimate_poses: estimate.len(),
            matched_poses: matched.len(),
            pairs: errors.len(),
            delta_frames: delta,
            all_pairs: options.all_pairs,
            alignment,
            translation_m: Statistics::from_errors(&translation)?,
            heading_error_deg: Statistics::from_errors(&heading)?,
        },
        errors,
    })
}
