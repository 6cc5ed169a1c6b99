//! After the first scan, extraction does not touch the heap: a counting global allocator
//! sees no allocation while the same extractor and output buffer process more scans.
//! (One test in this binary, so no other test allocates meanwhile.)

mod extraction_support;

use extraction_support::{furnished_room, simulate, Rng, Scanner};
use lrf_lines::{ExtractionParams, LineExtractor};
use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

struct Counting;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

// SAFETY: forwards to the system allocator; only counts calls.
#[allow(unsafe_code)]
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: same contract as the caller's.
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        // SAFETY: same contract as the caller's.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn steady_state_extraction_does_not_allocate() {
    let room = furnished_room();
    let scanner = Scanner::new(180_f64.to_radians(), 0.25_f64.to_radians());
    let mut rng = Rng::new(5);
    let scans: Vec<Vec<f32>> = (0..5)
        .map(|_| simulate(&room.walls, &room.pose, &scanner, 0.01, 0.0, &mut rng))
        .collect();
    let as_scan = |ranges| scanner.scan(ranges);
    let mut extractor = LineExtractor::new(ExtractionParams::default()).unwrap();
    let mut out = Vec::with_capacity(64);
    extractor.extract(&as_scan(&scans[0]), &mut out).unwrap();
    assert!(out.len() > 5);
    let before = ALLOCATIONS.load(Ordering::Relaxed);
    for ranges in &scans[1..] {
        extractor.extract(&as_scan(ranges), &mut out).unwrap();
    }
    assert_eq!(ALLOCATIONS.load(Ordering::Relaxed) - before, 0);
}
