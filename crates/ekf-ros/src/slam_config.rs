//! The `[slam]` section of the configuration: how `ekf map build --slam` and
//! `ekf replay --grow-map` pick key scans, close loops, weigh the pose graph's edges and
//! match scans (docs/maps.md). The SLAM code is in [`crate::slam`]; its settings are here
//! so that the configuration file does not depend on it.

use ekf_core::setting::{check, Expected, InvalidSetting};
use ekf_core::{angle_diff, Pose2};
use lrf_lines::MapBuilderParams;
use serde::{Deserialize, Serialize};

/// The settings of the SLAM map builder (`[slam]` in the configuration). The defaults
/// suit an indoor robot with a 2D laser of 8–80 m range.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SlamParams {
    /// A scan this far (m) from the last key scan is a key scan.
    pub key_distance: f64,
    /// ... or turned this much (rad).
    pub key_angle: f64,
    /// The filter localizes in the map of the key scans up to this path length (m)
    /// behind the newest.
    pub local_map_path: f64,
    /// A loop closure ties a key scan to old ones at least this path length (m) behind.
    pub loop_min_path: f64,
    /// Searched radius (m) around the filter's pose for a loop closure: `loop_radius +
    /// loop_drift · s`, `s` the path since the old key scan or the last closure,
    /// at most `loop_max_radius`.
    pub loop_radius: f64,
    /// See `loop_radius` (m per m driven).
    pub loop_drift: f64,
    /// See `loop_radius` (m). A bound on the search's cost, not its safety: a closure far
    /// from where the graph has the robot is refused by the graph's consistency test
    /// (freiburg-campus, outdoors, needs more than 20 m after its long loops).
    pub loop_max_radius: f64,
    /// Largest heading correction (rad) a loop closure may make.
    pub loop_max_turn: f64,
    /// Path (m) after a closure before the next is searched for.
    pub loop_cooldown_path: f64,
    /// A loop closure is searched for with the walls of the key scans up to this path
    /// (m) before the newest, placed by the front end and fused: a few scans' walls,
    /// where one scan's two to six lines are often ambiguous; their lines refine the
    /// pose found.
    pub chain_path: f64,
    /// Old key scans within this distance (m) of the closure's anchor make its submap ...
    pub submap_radius: f64,
    /// ... the nearest this many of them.
    pub submap_max_keys: usize,
    /// Key scans after a hypothesis that must fit its correction before it is a closure.
    pub verify_key_scans: usize,
    /// How close (m) a confirming key scan's pose must come to the correction's.
    pub verify_distance: f64,
    /// ... and its heading (rad).
    pub verify_angle: f64,
    /// Prior standard deviation (m) of the refinement's EKF update.
    pub refine_sigma_xy: f64,
    /// ... of its heading (rad).
    pub refine_sigma_theta: f64,
    /// A scan the filter's pose does not explain is fused again with the covariance
    /// widened by this standard deviation of position (m) ...
    pub rematch_sigma_xy: f64,
    /// ... and of heading (rad): about three times the heading error of the odometry of
    /// one scan interval on the shared logs (RMS 2.6° on ACES).
    pub rematch_sigma_theta: f64,
    /// Fewest lines that must fuse in a refinement.
    pub min_loop_lines: usize,

    /// Odometry edge: position standard deviation per key step (m) ...
    pub odometry_sigma_xy: f64,
    /// ... plus this per metre of the step.
    pub odometry_sigma_xy_per_m: f64,
    /// Odometry edge: heading standard deviation per key step (rad) ...
    pub odometry_sigma_theta: f64,
    /// ... plus this per radian turned.
    pub odometry_sigma_theta_per_rad: f64,
    /// Gauss–Newton iterations per optimisation, at most.
    pub max_iterations: usize,
    /// How the key scans' lines are fused into walls.
    pub map_builder: MapBuilderParams,
    /// The scan matcher that corrects each scan's pose, and each loop closure's, with the
    /// scan's points.
    pub scan_match: MatchParams,
}

impl Default for SlamParams {
    fn default() -> Self {
        Self {
            key_distance: 0.5,
            key_angle: 15f64.to_radians(),
            local_map_path: 10.0,
            loop_min_path: 15.0,
            loop_radius: 1.0,
            loop_drift: 0.1,
            loop_max_radius: 50.0,
            loop_max_turn: 20f64.to_radians(),
            loop_cooldown_path: 2.0,
            chain_path: 3.0,
            submap_radius: 8.0,
            submap_max_keys: 40,
            verify_key_scans: 2,
            verify_distance: 0.3,
            verify_angle: 3f64.to_radians(),
            refine_sigma_xy: 0.15,
            refine_sigma_theta: 3f64.to_radians(),
            rematch_sigma_xy: 0.3,
            rematch_sigma_theta: 0.15,
            min_loop_lines: 3,
            odometry_sigma_xy: 0.02,
            odometry_sigma_xy_per_m: 0.03,
            odometry_sigma_theta: 0.3f64.to_radians(),
            odometry_sigma_theta_per_rad: 0.03,
            max_iterations: 20,
            map_builder: MapBuilderParams::default(),
            scan_match: MatchParams::default(),
        }
    }
}

impl SlamParams {
    /// Distances and standard deviations positive, angles in radians, rates, tolerances
    /// and the map builder's gap not negative, its gate probability in (0, 1), the scan
    /// matcher's settings valid ([`MatchParams::validate`]).
    pub fn validate(&self) -> Result<(), InvalidSetting> {
        for (key, value) in [
            ("key_distance", self.key_distance),
            ("local_map_path", self.local_map_path),
            ("loop_min_path", self.loop_min_path),
            ("loop_radius", self.loop_radius),
            ("loop_max_radius", self.loop_max_radius),
            ("submap_radius", self.submap_radius),
            ("verify_distance", self.verify_distance),
            ("refine_sigma_xy", self.refine_sigma_xy),
            ("rematch_sigma_xy", self.rematch_sigma_xy),
            ("odometry_sigma_xy", self.odometry_sigma_xy),
            ("odometry_sigma_theta", self.odometry_sigma_theta),
        ] {
            check(key, value, Expected::Positive)?;
        }
        for (key, value) in [
            ("key_angle", self.key_angle),
            ("loop_max_turn", self.loop_max_turn),
            ("verify_angle", self.verify_angle),
            ("refine_sigma_theta", self.refine_sigma_theta),
            ("rematch_sigma_theta", self.rematch_sigma_theta),
        ] {
            check(key, value, Expected::Radians)?;
            check(key, value, Expected::Positive)?;
        }
        for (key, value) in [
            ("loop_drift", self.loop_drift),
            ("loop_cooldown_path", self.loop_cooldown_path),
            ("chain_path", self.chain_path),
            ("odometry_sigma_xy_per_m", self.odometry_sigma_xy_per_m),
            (
                "odometry_sigma_theta_per_rad",
                self.odometry_sigma_theta_per_rad,
            ),
            ("map_builder.tolerance_rho", self.map_builder.tolerance_rho),
            (
                "map_builder.tolerance_beta",
                self.map_builder.tolerance_beta,
            ),
            ("map_builder.max_gap", self.map_builder.max_gap),
        ] {
            check(key, value, Expected::MetresWithin(1e6))?;
            if value < 0.0 {
                check(key, value, Expected::Positive)?;
            }
        }
        check(
            "map_builder.gate_probability",
            self.map_builder.gate_probability,
            Expected::Probability,
        )?;
        self.scan_match.validate()
    }

    /// Whether a scan at `pose` is a key scan after the last one at `last`: it is
    /// `key_distance` from it or turned `key_angle`.
    pub fn is_key(&self, last: &Pose2<f64>, pose: &Pose2<f64>) -> bool {
        (pose.x - last.x).hypot(pose.y - last.y) >= self.key_distance
            || angle_diff(pose.theta, last.theta).abs() >= self.key_angle
    }
}

/// The reference keeps one point per square of this size (m), the first seen: key scans
/// that overlap do not multiply the points a match searches through.
pub const REFERENCE_VOXEL: f64 = 0.05;

/// The farthest (m) a scan matcher's point may be from its reference point: a match
/// farther than a few metres is no longer a correction of a filter's pose.
const MAX_MATCH_DISTANCE: f64 = 5.0;

/// The settings of the scan matcher (`[slam.scan_match]`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct MatchParams {
    /// A point farther than this (m) from every reference point is not matched.
    pub max_distance: f64,
    /// Standard deviation (m) of a point's distance to its surface: the range noise and
    /// the reference's own.
    pub sigma: f64,
    /// Prior standard deviation (m) of the filter's position ...
    pub prior_sigma_xy: f64,
    /// ... and heading (rad).
    pub prior_sigma_theta: f64,
    /// Gauss–Newton iterations at most.
    pub max_iterations: usize,
    /// Share of the scan's points that must be matched for the result to stand.
    pub min_matched_share: f64,
}

impl Default for MatchParams {
    /// A laser of a few centimetres' range noise, matched within 0.3 m of where the filter
    /// put it.
    fn default() -> Self {
        Self {
            max_distance: 0.3,
            sigma: 0.05,
            prior_sigma_xy: 0.3,
            prior_sigma_theta: 0.15,
            max_iterations: 20,
            min_matched_share: 0.3,
        }
    }
}

impl MatchParams {
    /// `max_distance` from [`REFERENCE_VOXEL`] to 5 m; standard deviations and the iteration
    /// count positive, the prior's
    /// heading in radians, the matched share a probability (a share in (0, 1)).
    pub fn validate(&self) -> Result<(), InvalidSetting> {
        // The reference grid's cells are `max_distance` wide: below the voxel a match
        // misses the reference's points, and a tiny value would make billions of cells.
        check(
            "scan_match.max_distance",
            self.max_distance,
            Expected::MetresIn(REFERENCE_VOXEL, MAX_MATCH_DISTANCE),
        )?;
        for (key, value) in [
            ("scan_match.sigma", self.sigma),
            ("scan_match.prior_sigma_xy", self.prior_sigma_xy),
            ("scan_match.prior_sigma_theta", self.prior_sigma_theta),
            ("scan_match.max_iterations", self.max_iterations as f64),
        ] {
            check(key, value, Expected::Positive)?;
        }
        check(
            "scan_match.prior_sigma_theta",
            self.prior_sigma_theta,
            Expected::Radians,
        )?;
        check(
            "scan_match.min_matched_share",
            self.min_matched_share,
            Expected::Probability,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn settings_out_of_range_are_named() {
        assert_eq!(SlamParams::default().validate(), Ok(()));
        let refused = |edit: fn(&mut SlamParams)| {
            let mut p = SlamParams::default();
            edit(&mut p);
            p.validate().unwrap_err().to_string()
        };
        assert_eq!(
            refused(|p| p.scan_match.max_distance = 0.001),
            "scan_match.max_distance: expected metres in [0.05, 5], found 0.001"
        );
        assert_eq!(
            refused(|p| p.scan_match.max_distance = 30.0),
            "scan_match.max_distance: expected metres in [0.05, 5], found 30"
        );
        assert_eq!(
            refused(|p| p.key_angle = 15.0),
            "key_angle: expected radians within ±2π (6.283), found 15 (degrees?)"
        );
    }

    #[test]
    fn a_key_scan_is_far_enough_or_turned_enough() {
        let p = SlamParams::default();
        let last = Pose2::new(1.0, 2.0, 0.1);
        assert!(!p.is_key(&last, &Pose2::new(1.3, 2.3, 0.2)));
        assert!(p.is_key(&last, &Pose2::new(1.3, 2.41, 0.1)), "0.51 m");
        assert!(p.is_key(&last, &Pose2::new(1.0, 2.0, 0.1 - 0.27)), "15.5°");
    }
}
