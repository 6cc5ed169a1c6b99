//! A Localizer step (predict, compass, scan) does not allocate once its buffers have grown.

#[path = "../../ekf-core/tests/alloc_support/mod.rs"]
mod alloc_support;
mod localizer_sim;
mod matching_support;

use alloc_support::allocations;
use localizer_sim::{commands, mount, ranges, scan, start, walls};
use lrf_lines::{Localizer, LocalizerConfig};
use matching_support::{map_of, Rng};
use nalgebra::Matrix3;

/// Ten steps of predict, compass and scan to let the buffers grow, then ten more,
/// counting allocations.
fn assert_steady_state_allocation_free(mut localizer: Localizer, what: &str) {
    let mut rng = Rng::new(3);
    let cmd = commands()[0];
    let r = ranges(&start(), &walls(), &mut rng);
    let scan = scan(&r);
    let step = |localizer: &mut Localizer| {
        localizer.predict_wheels(&cmd).unwrap();
        localizer.update_compass(0.0).unwrap();
        localizer.update_scan(&scan).unwrap()
    };
    for _ in 0..10 {
        step(&mut localizer);
    }
    let before = allocations();
    for _ in 0..10 {
        assert!(step(&mut localizer).fused > 0, "{what}");
    }
    assert_eq!(allocations(), before, "{what}");
}

fn config() -> LocalizerConfig {
    LocalizerConfig {
        laser_mount: mount(),
        ..LocalizerConfig::default()
    }
}

/// One test (the allocation counter is global to the process): with a given map, and with
/// a first-scan map, whose errors and their saved copy live in buffers that stop growing.
#[test]
fn a_localizer_step_is_allocation_free_in_steady_state() {
    let p0 = Matrix3::identity() * 1e-4;
    let given = Localizer::new(config(), start(), p0, map_of(&walls())).unwrap();
    assert_steady_state_allocation_free(given, "given map");
    let first_scan = Localizer::with_first_scan_map(config(), start(), p0).unwrap();
    assert_steady_state_allocation_free(first_scan, "first-scan map");
}
