//! A scan that the filter's pose does not explain, fused again with a wider covariance:
//! odometry that erred more than the filter's prediction allows makes the gate refuse the
//! right walls, and a map grown from the scans after it would keep the error.

use super::SlamParams;
use ekf_core::Pose2;
use ekf_fusion::Fuser;
use lrf_lines::{fit_poses, LineMap, ObservedLine, RelocalizeParams};
use nalgebra::{Matrix3, Vector3};

/// A scan that the filter's pose does not explain (fewer than three lines or half its
/// line length on walls of the local map, as the relocalization search scores it) is
/// fused again with the covariance widened by `rematch_sigma_xy` and
/// `rematch_sigma_theta` (the position only when a compass holds the heading); if the
/// pose it gives puts at least as many lines (and two) on walls and scores `min_margin`
/// times better (and, with a compass, half the line length), it is kept, otherwise the
/// filter is put back (each restart forgets a compass lock-out, as any restart does).
/// Returns the new pose.
pub fn rematch(
    fuser: &mut Fuser,
    lines: &[ObservedLine],
    params: &SlamParams,
) -> Option<Pose2<f64>> {
    let mount = fuser.localizer().config().laser_mount;
    let map = fuser.localizer().map();
    if map.is_empty() || lines.is_empty() {
        return None;
    }
    let search = RelocalizeParams::default();
    let fit = |map: &LineMap, pose: Pose2<f64>| {
        let fits = fit_poses(lines, map, &mount, &[pose], &search);
        (fits.fits.first().copied(), fits.observed_length)
    };
    let (here, covariance) = (fuser.localizer().pose(), *fuser.localizer().covariance());
    let (Some(before), observed) = fit(map, here) else {
        return None;
    };
    if search.explains(before.inliers, before.score, observed) {
        return None;
    }
    // With a compass the heading is held by it: only the position is widened, and a
    // position found so must put half the scan's line length on walls (a position-only
    // re-fit slides along walls easily; a turn that makes lines fit is rarer evidence).
    let compass = fuser.mode().uses_compass();
    let sth = match compass {
        true => 0.0,
        false => params.rematch_sigma_theta,
    };
    let sxy = params.rematch_sigma_xy;
    let widened =
        covariance + Matrix3::from_diagonal(&Vector3::new(sxy * sxy, sxy * sxy, sth * sth));
    let filter = fuser.localizer_mut();
    filter.reset(here, widened).ok()?;
    let refused = filter.update_lines(lines).is_err();
    let pose = filter.pose();
    let after = fit(filter.map(), pose).0;
    let better = after.is_some_and(|a| {
        a.inliers >= before.inliers.max(2)
            && a.score >= search.min_margin * before.score
            && (!compass || a.score >= 0.5 * observed)
    });
    if refused || !better {
        filter.reset(here, covariance).ok()?;
        return None;
    }
    Some(pose)
}
