//! After the first scan, extraction does not touch the heap: a counting global allocator
//! sees no allocation while the same extractor and output buffer process more scans.
//! (One test in this binary, so no other test allocates meanwhile.)

#[path = "../../ekf-core/tests/alloc_support/mod.rs"]
mod alloc_support;
mod extraction_support;

use alloc_support::allocations;
use extraction_support::{furnished_room, simulate, Rng, Scanner};
use lrf_lines::{ExtractionParams, LineExtractor};

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
    let before = allocations();
    for ranges in &scans[1..] {
        extractor.extract(&as_scan(ranges), &mut out).unwrap();
    }
    assert_eq!(allocations() - before, 0);
}
