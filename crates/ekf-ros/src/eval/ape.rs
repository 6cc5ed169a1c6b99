//! Absolute pose error (APE, also called ATE): the pose-by-pose difference between the
//! aligned estimate and the reference, as `evo_ape` computes it.

use super::{
    align_estimate, associate, Alignment, AlignmentOptions, AssociationOptions, EvalError,
    Statistics,
};
use crate::trajectory::Trajectory;
use ekf_core::angle_diff;
use serde::Serialize;

/// Options of [`ape`]: pairing and alignment (`evo_ape`'s defaults: 10 ms, no alignment).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ApeOptions {
    /// How poses are paired in time.
    pub association: AssociationOptions,
    /// How the estimate is aligned before the errors are taken.
    pub alignment: AlignmentOptions,
}

/// The error of one matched pose, estimate minus reference.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PoseError {
    /// Stamp of the reference pose (ns).
    pub t_ns: u64,
    /// `x_est − x_ref` (m).
    pub dx: f64,
    /// `y_est − y_ref` (m).
    pub dy: f64,
    /// Position error `√(dx² + dy²)` (m): `evo`'s translation part.
    pub translation: f64,
    /// Signed heading error `wrap(θ_est − θ_ref)` in (−180°, 180°] (degrees).
    pub heading_deg: f64,
}

/// What `evo_ape` reports, for a planar trajectory. Serializes to JSON.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ApeSummary {
    /// Poses in the reference file.
    pub reference_poses: usize,
    /// Poses in the estimate file.
    pub estimate_poses: usize,
    /// Poses paired by time stamp; all statistics are over these.
    pub matched_poses: usize,
    /// The alignment applied to the estimate, if any.
    pub alignment: Option<Alignment>,
    /// Statistics of the position error `|p_est − p_ref|` (m); `evo_ape -r trans_part`
    /// (the default), whose `rmse` is the ATE.
    pub translation_m: Statistics,
    /// Statistics of the absolute wrapped heading error `|wrap(θ_est − θ_ref)|`
    /// (degrees). Our planar extra; it equals `evo_ape -r angle_deg` for planar poses.
    pub heading_error_deg: Statistics,
}

/// The APE: its summary and the error of every matched pose (for plots).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Ape {
    /// Statistics and counts.
    pub summary: ApeSummary,
    /// One error per matched pose, in matching order.
    pub errors: Vec<PoseError>,
}

/// The absolute pose error of `estimate` against `reference`.
///
/// Steps, as `evo_ape`: pair the poses by time stamp ([`super::associate`]), align the
/// paired estimate if asked ([`super::align_estimate`]), then per pair
/// `e_k = |p_est,k − p_ref,k|` and `h_k = |wrap(θ_est,k − θ_ref,k)|`, summarised by
/// [`Statistics`].
pub fn ape(
    reference: &Trajectory,
    estimate: &Trajectory,
    options: &ApeOptions,
) -> Result<Ape, EvalError> {
    let matched = associate(reference, estimate, &options.association)?;
    let (aligned, alignment) = align_estimate(&matched, &options.alignment)?;
    let errors: Vec<PoseError> = matched
        .reference
        .iter()
        .zip(&aligned)
        .map(|(r, e)| {
            let (dx, dy) = (e.pose.x - r.pose.x, e.pose.y - r.pose.y);
            PoseError {
                t_ns: r.t_ns,
                dx,
                dy,
                translation: dx.hypot(dy),
                heading_deg: angle_diff(e.pose.theta, r.pose.theta).to_degrees(),
            }
        })
        .collect();
    let translation: Vec<f64> = errors.iter().map(|e| e.translation).collect();
    let heading: Vec<f64> = errors.iter().map(|e| e.heading_deg.abs()).collect();
    Ok(Ape {
        summary: ApeSummary {
            reference_poses: reference.len(),
            estimate_poses: estimate.len(),
            matched_poses: matched.len(),
            alignment,
            translation_m: Statistics::from_errors(&translation)?,
            heading_error_deg: Statistics::from_errors(&heading)?,
        },
        errors,
    })
}
