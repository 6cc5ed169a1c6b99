//! A Localizer step (predict, compass, scan) does not allocate once its buffers have grown.
// A counting global allocator needs `unsafe impl GlobalAlloc`; it only forwards to the
// system allocator.
#![allow(unsafe_code)]

mod localizer_sim;
mod matching_support;

use localizer_sim::{commands, mount, ranges, scan, start, walls};
use lrf_lines::{Localizer, LocalizerConfig};
use matching_support::{map_of, Rng};
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
fn a_localizer_step_is_allocation_free_in_steady_state() {
    let config = LocalizerConfig {
        laser_mount: mount(),
        ..LocalizerConfig::default()
    };
    let walls = walls();
    let mut localizer =
        Localizer::new(config, start(), Matrix3::identity() * 1e-4, map_of(&walls)).unwrap();
    let mut rng = Rng::new(3);
    let cmd = commands()[0];
    let r = ranges(&start(), &walls, &mut rng);
    let scan = scan(&r);
    for _ in 0..3 {
        localizer.update_scan(&scan).unwrap();
    }
    let before = ALLOCATIONS.load(Ordering::Relaxed);
    for _ in 0..10 {
        localizer.predict_wheels(&cmd).unwrap();
        localizer.update_compass(0.0).unwrap();
        let report = localizer.update_scan(&scan).unwrap();
        assert!(report.fused > 0);
    }
    assert_eq!(ALLOCATIONS.load(Ordering::Relaxed), before);
}
