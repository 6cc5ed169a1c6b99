//! `ekf evaluate EST --truth REF`: absolute and relative pose errors as `evo` defines them.

use crate::eval::{ape, rpe, AlignMode, ApeOptions, ApeSummary, EvalError, RpeOptions, RpeSummary};
use crate::trajectory::Trajectory;
use crate::tum::{read_tum_file, TumError};
use serde::Serialize;
use std::fmt::Write as _;
use std::path::Path;

/// Why an evaluation failed.
#[derive(Debug, thiserror::Error)]
pub enum EvaluateError {
    /// A trajectory file could not be read.
    #[error(transparent)]
    Tum(#[from] TumError),
    /// The trajectories could not be compared (no poses matched in time, …).
    #[error("{0}")]
    Eval(#[from] EvalError),
}

/// What `ekf evaluate` reports; `--json` prints it as JSON.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct EvaluationReport {
    /// Absolute pose error (ATE: `ape.translation_m.rmse`).
    pub ape: ApeSummary,
    /// Relative pose error between consecutive matched poses.
    pub rpe: RpeSummary,
}

/// Reads a trajectory file (TUM text).
pub fn load_trajectory(path: &Path) -> Result<Trajectory, EvaluateError> {
    Ok(read_tum_file(path)?)
}

/// Compares `estimate` with `reference`: APE and RPE (delta 1 frame), in the same frame
/// unless `align` asks for a rigid (SE(2)) Umeyama alignment first, as `evo -a`.
pub fn evaluate(
    estimate: &Trajectory,
    reference: &Trajectory,
    align: bool,
) -> Result<EvaluationReport, EvaluateError> {
    let mut ape_options = ApeOptions::default();
    let mut rpe_options = RpeOptions::default();
    if align {
        ape_options.alignment.mode = AlignMode::Rigid;
        rpe_options.alignment.mode = AlignMode::Rigid;
    }
    Ok(EvaluationReport {
        ape: ape(reference, estimate, &ape_options)?.summary,
        rpe: rpe(reference, estimate, &rpe_options)?.summary,
    })
}

impl EvaluationReport {
    /// A short human-readable table.
    pub fn to_table(&self) -> String {
        let mut s = String::new();
        let a = &self.ape;
        let _ = writeln!(
            s,
            "matched poses: {} (estimate {}, reference {})",
            a.matched_poses, a.estimate_poses, a.reference_poses
        );
        let _ = writeln!(
            s,
            "{:<28} {:>10} {:>10} {:>10} {:>10}",
            "", "rmse", "mean", "median", "max"
        );
        let rows = [
            ("APE position (m)", &a.translation_m),
            ("APE heading (deg)", &a.heading_error_deg),
            ("RPE position (m/frame)", &self.rpe.translation_m),
            ("RPE heading (deg/frame)", &self.rpe.heading_error_deg),
        ];
        for (name, st) in rows {
            let _ = writeln!(
                s,
                "{name:<28} {:>10.4} {:>10.4} {:>10.4} {:>10.4}",
                st.rmse, st.mean, st.median, st.max
            );
        }
        s
    }
}
