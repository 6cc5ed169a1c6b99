//! Matching does not allocate once its reusable result has grown to size.

#[path = "../../ekf-core/tests/alloc_support/mod.rs"]
mod alloc_support;
mod matching_support;

use alloc_support::allocations;
use ekf_core::{Ekf, Pose2};
use lrf_lines::{MatchParams, MatchResult, Matcher};
use matching_support::{map_of, observe_all, rect_room, NOISE};
use nalgebra::Matrix3;

#[test]
fn matching_is_allocation_free_in_steady_state() {
    let walls = rect_room(-1.0, -1.0, 5.0, 3.0);
    let map = map_of(&walls);
    let pose = Pose2::new(1.0, 1.0, 0.2);
    let observed = observe_all(&walls, &pose, NOISE);
    let ekf = Ekf::new(pose, Matrix3::identity() * 0.01).unwrap();
    let matcher = Matcher::new(MatchParams::default()).unwrap();
    let mut out = MatchResult::new();
    matcher.match_lines(&observed, &map, &ekf, &Pose2::identity(), &mut out);
    let before = allocations();
    for _ in 0..10 {
        matcher.match_lines(&observed, &map, &ekf, &Pose2::identity(), &mut out);
    }
    assert_eq!(allocations(), before);
    assert_eq!(out.matches().len(), 4);
}
