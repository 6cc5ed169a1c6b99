//! Our APE/RPE against numbers frozen from `evo` 1.38 (`tests/golden/make_evo_golden.py`
//! ran `evo_ape`/`evo_rpe tum evo_ref.txt evo_est.txt …` with `-r trans_part` and
//! `-r angle_deg`): every statistic must agree to 1e-9.

use ekf_cli::eval::{ape, rpe, AlignMode, AlignmentOptions, ApeOptions, RpeOptions, Statistics};
use ekf_cli::trajectory::Trajectory;
use ekf_cli::tum::read_tum_file;
use serde_json::Value;
use std::path::PathBuf;

fn golden(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/golden")
        .join(name)
}

/// (reference, estimate); `swapped` exchanges the files, as the `*_swapped` cases do,
/// so that the other trajectory is the shorter one that drives the association.
fn inputs(swapped: bool) -> (Trajectory, Trajectory) {
    let a = read_tum_file(&golden("evo_ref.txt")).unwrap();
    let b = read_tum_file(&golden("evo_est.txt")).unwrap();
    if swapped {
        (b, a)
    } else {
        (a, b)
    }
}

fn expected(case: &str) -> Value {
    let text = std::fs::read_to_string(golden("evo_expected.json")).unwrap();
    let doc: Value = serde_json::from_str(&text).unwrap();
    doc["cases"][case].clone()
}

fn assert_stats(case: &str, what: &str, ours: &Statistics, theirs: &Value) {
    let ours = serde_json::to_value(ours).unwrap();
    for key in ["rmse", "mean", "median", "std", "min", "max", "sse"] {
        let (a, b) = (ours[key].as_f64().unwrap(), theirs[key].as_f64().unwrap());
        assert!(
            (a - b).abs() <= 1e-9,
            "{case} {what} {key}: ours {a}, evo {b}"
        );
    }
}

/// The count and both statistics of one case against evo's.
fn assert_case(case: &str, count: usize, translation: &Statistics, heading: &Statistics) {
    let want = expected(case);
    assert_eq!(count as u64, want["count"].as_u64().unwrap(), "{case}");
    assert_stats(case, "translation", translation, &want["translation_m"]);
    assert_stats(case, "heading", heading, &want["heading_error_deg"]);
}

fn check_ape(case: &str, alignment: AlignmentOptions) {
    let (reference, estimate) = inputs(case.ends_with("_swapped"));
    let options = ApeOptions {
        alignment,
        ..ApeOptions::default()
    };
    let result = ape(&reference, &estimate, &options).unwrap().summary;
    assert_case(
        case,
        result.matched_poses,
        &result.translation_m,
        &result.heading_error_deg,
    );
}

fn check_rpe(case: &str, delta_frames: usize, all_pairs: bool) {
    let (reference, estimate) = inputs(case.ends_with("_swapped"));
    let options = RpeOptions {
        delta_frames,
        all_pairs,
        ..RpeOptions::default()
    };
    let result = rpe(&reference, &estimate, &options).unwrap().summary;
    assert_case(
        case,
        result.pairs,
        &result.translation_m,
        &result.heading_error_deg,
    );
}

#[test]
fn ape_without_alignment_equals_evo() {
    check_ape("ape_none", AlignmentOptions::default());
    check_ape("ape_none_swapped", AlignmentOptions::default());
}

#[test]
fn ape_with_rigid_alignment_equals_evo() {
    check_ape(
        "ape_align",
        AlignmentOptions {
            mode: AlignMode::Rigid,
            n_to_align: None,
        },
    );
}

#[test]
fn ape_with_similarity_alignment_equals_evo() {
    check_ape(
        "ape_align_scale",
        AlignmentOptions {
            mode: AlignMode::RigidAndScale,
            n_to_align: None,
        },
    );
}

#[test]
fn ape_aligned_on_first_poses_equals_evo() {
    check_ape(
        "ape_align_first_20",
        AlignmentOptions {
            mode: AlignMode::Rigid,
            n_to_align: Some(20),
        },
    );
}

#[test]
fn rpe_equals_evo() {
    check_rpe("rpe_delta_1", 1, false);
    check_rpe("rpe_delta_3", 3, false);
    check_rpe("rpe_delta_3_all_pairs", 3, true);
    check_rpe("rpe_delta_1_swapped", 1, false);
}
