//! Pairing by time stamp: evo's nearest-time rule, worked through by hand (each case
//! away from exact float ties was checked against evo's `matching_time_indices`).

use ekf_cli::eval::{associate, AssociationOptions, EvalError};
use ekf_cli::trajectory::Trajectory;
use ekf_core::Pose2;

const MS: u64 = 1_000_000;

/// Poses at the given stamps (ms); x holds the index so pairs can be read back.
fn at(stamps_ms: &[u64]) -> Trajectory {
    let mut t = Trajectory::new();
    for (k, &ms) in stamps_ms.iter().enumerate() {
        t.push(ms * MS, Pose2::new(k as f64, 0.0, 0.0));
    }
    t
}

/// The index pairs `(reference, estimate)` of an association.
fn pairs(
    reference: &Trajectory,
    estimate: &Trajectory,
    options: &AssociationOptions,
) -> Vec<(usize, usize)> {
    let m = associate(reference, estimate, options).unwrap();
    m.reference
        .iter()
        .zip(&m.estimate)
        .map(|(r, e)| (r.pose.x as usize, e.pose.x as usize))
        .collect()
}

#[test]
fn nearest_stamp_within_ten_milliseconds() {
    let reference = at(&[0, 100, 200, 300, 400, 500]);
    // 103 → 100; 192 → 200; 320 is 20 ms from 300: dropped; 499 → 500.
    let estimate = at(&[103, 192, 320, 499]);
    let p = pairs(&reference, &estimate, &AssociationOptions::default());
    assert_eq!(p, vec![(1, 0), (2, 1), (5, 3)]);
}

#[test]
fn a_difference_of_exactly_max_diff_is_accepted() {
    let reference = at(&[0, 100]);
    let estimate = at(&[110]);
    assert_eq!(
        pairs(&reference, &estimate, &AssociationOptions::default()),
        vec![(1, 0)]
    );
    let tight = AssociationOptions {
        max_diff_ns: 10 * MS - 1,
        ..AssociationOptions::default()
    };
    assert!(associate(&reference, &estimate, &tight).is_err());
}

#[test]
fn the_shorter_trajectory_drives_the_matching() {
    // Reference shorter: each reference pose takes its nearest estimate pose; estimate
    // poses 1 and 2 are left out.
    let reference = at(&[0, 100]);
    let estimate = at(&[1, 4, 97, 102]);
    assert_eq!(
        pairs(&reference, &estimate, &AssociationOptions::default()),
        vec![(0, 0), (1, 3)]
    );
    // Equal lengths: the estimate is the short one, as in evo. Two estimate poses near
    // the same reference pose both take it (evo is one-to-one on the short side only).
    let reference = at(&[0, 100, 200]);
    let estimate = at(&[1, 4, 200]);
    assert_eq!(
        pairs(&reference, &estimate, &AssociationOptions::default()),
        vec![(0, 0), (0, 1), (2, 2)]
    );
}

#[test]
fn ties_go_to_the_earlier_stamp() {
    let reference = at(&[0, 10, 20]);
    let estimate = at(&[5, 15]);
    assert_eq!(
        pairs(&reference, &estimate, &AssociationOptions::default()),
        vec![(0, 0), (1, 1)]
    );
}

#[test]
fn unsorted_stamps_use_a_linear_search() {
    let reference = at(&[300, 100, 200, 0]);
    let estimate = at(&[201, 2, 299]);
    assert_eq!(
        pairs(&reference, &estimate, &AssociationOptions::default()),
        vec![(2, 0), (3, 1), (0, 2)]
    );
}

#[test]
fn time_offset_is_added_to_the_estimate() {
    let reference = at(&[1000, 1100, 1200]);
    let estimate = at(&[0, 100, 200]);
    let shifted = AssociationOptions {
        t_offset_ns: 1000 * MS as i64,
        ..AssociationOptions::default()
    };
    let m = associate(&reference, &estimate, &shifted).unwrap();
    assert_eq!(m.len(), 3);
    // The stamps themselves are kept.
    assert_eq!(m.estimate.samples[0].t_ns, 0);
    assert_eq!(m.reference.samples[0].t_ns, 1000 * MS);
}

#[test]
fn no_match_is_an_error_with_the_numbers() {
    let err = associate(&at(&[0, 100]), &at(&[500]), &AssociationOptions::default()).unwrap_err();
    assert_eq!(
        err,
        EvalError::NoMatches {
            reference_poses: 2,
            estimate_poses: 1,
            max_diff_ns: 10 * MS,
            t_offset_ns: 0
        }
    );
    assert!(err.to_string().contains("max. time difference 10000000 ns"));
    assert!(associate(
        &Trajectory::new(),
        &at(&[0]),
        &AssociationOptions::default()
    )
    .is_err());
}
