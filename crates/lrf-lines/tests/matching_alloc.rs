//! Matching does not allocate once its reusable result has grown to size.
// A counting global allocator needs `unsafe impl GlobalAlloc`; it only forwards to the
// system allocator.
#![allow(unsafe_code)]

mod matching_support;

use ekf_core::{Ekf, Pose2};
use lrf_lines::{MatchParams, MatchResult, Matcher};
use matching_support::{map_of, observe_all, rect_room, NOISE};
use nalgebra::Matrix3;
use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

struct Counting;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

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
    let before = ALLOCATIONS.load(Ordering::Relaxed);
    for _ in 0..10 {
        matcher.match_lines(&observed, &map, &ekf, &Pose2::identity(), &mut out);
    }
    assert_eq!(ALLOCATIONS.load(Ordering::Relaxed), before);
    assert_eq!(out.matches().len(), 4);
}
