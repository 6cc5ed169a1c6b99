//! The one error type of the evaluation: what was wrong with the trajectories or the
//! options, with the numbers needed to fix it.

/// Why an evaluation could not be computed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum EvalError {
    /// No pose of one trajectory has a pose of the other within the allowed time
    /// difference (`evo`: "found no matching timestamps").
    #[error(
        "found no matching time stamps between the reference ({reference_poses} poses) and \
         the estimate ({estimate_poses} poses) with max. time difference {max_diff_ns} ns \
         and time offset {t_offset_ns} ns"
    )]
    NoMatches {
        /// Poses in the reference.
        reference_poses: usize,
        /// Poses in the estimate.
        estimate_poses: usize,
        /// The allowed time difference (ns).
        max_diff_ns: u64,
        /// The offset added to the estimate's stamps (ns).
        t_offset_ns: i64,
    },
    /// Statistics of an empty set of errors were asked for.
    #[error("no errors to compute statistics of")]
    NoErrors,
    /// The estimate's positions do not determine a rotation (all alignment poses at one
    /// point, or none selected).
    #[error(
        "degenerate point set: the {poses} estimate positions used for alignment do not \
         determine a rotation (all at one point?)"
    )]
    DegenerateAlignment {
        /// Number of poses used for the alignment.
        poses: usize,
    },
    /// The RPE step must be at least one frame.
    #[error("RPE delta must be at least 1 frame, got {delta}")]
    InvalidDelta {
        /// The requested step.
        delta: usize,
    },
    /// Too few matched poses for one pair at the requested RPE step.
    #[error("RPE delta = {delta} frames produced no pose pairs from {poses} matched poses")]
    NoPairs {
        /// The requested step (frames).
        delta: usize,
        /// Matched poses available.
        poses: usize,
    },
}
