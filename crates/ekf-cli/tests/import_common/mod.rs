//! Helpers shared by the importer tests: finding the real logs, comparing poses.

#![allow(dead_code)] // each test binary uses its own subset

use ekf_cli::import::ImportRecord;
use ekf_core::Pose2;
use std::path::PathBuf;

/// The real log `name` in the project's `shared/data`: the first ancestor of the crate
/// that has `shared/data/<name>` (the repo at `/work/main`, a worktree, or CI's clone
/// with `shared/` beside it).
pub fn shared_data(name: &str) -> PathBuf {
    let manifest = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    manifest
        .ancestors()
        .map(|dir| dir.join("shared").join("data").join(name))
        .find(|path| path.exists())
        .unwrap_or_else(|| {
            panic!(
                "shared/data/{name} not found beside any ancestor of {}",
                manifest.display()
            )
        })
}

/// Asserts two poses agree to `tol` in every component (heading difference wrapped).
#[track_caller]
pub fn assert_pose(actual: &Pose2<f64>, expected: (f64, f64, f64), tol: f64) {
    let dtheta = ekf_core::wrap_angle(actual.theta - expected.2);
    assert!(
        (actual.x - expected.0).abs() <= tol
            && (actual.y - expected.1).abs() <= tol
            && dtheta.abs() <= tol,
        "pose {actual:?} != {expected:?}"
    );
}

/// The record type's name, for compact assertions on sequences.
pub fn kind(record: &ImportRecord) -> &'static str {
    match record {
        ImportRecord::Odometry(_) => "odom",
        ImportRecord::Scan(_) => "scan",
        ImportRecord::Reference(_) => "ref",
        ImportRecord::Compass(_) => "compass",
    }
}
