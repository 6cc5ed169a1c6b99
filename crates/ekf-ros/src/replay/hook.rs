//! What the replay loop hands each fused scan to: a map that grows with the run
//! (`--grow-map`), a SLAM front end (`ekf map build --slam`).

use super::ReplayError;
use ekf_fusion::{Fuser, Scan, ScanFused};

/// Called by the replay loop after each scan's update and its outputs, before the pose
/// is recorded: a change the hook makes to the filter (a map, a corrected pose) is in the
/// pose recorded for the scan and in everything fused after it.
pub trait ScanHook {
    /// `now`: the scan's stamp (ns); `fused`: what the scan did; `scan`: its ranges;
    /// `fuser`: the filter, with
    /// the scan's lines (sensor frame) in `fuser.localizer().last_lines()`. Returns whether
    /// the filter's map was replaced (the output bag then publishes it again).
    fn scan_fused(
        &mut self,
        now: u64,
        fused: &ScanFused,
        scan: &Scan,
        fuser: &mut Fuser,
    ) -> Result<bool, ReplayError>;
}
