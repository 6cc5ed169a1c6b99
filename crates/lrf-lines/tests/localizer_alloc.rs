//! A Localizer step (predict, compass, scan) does not allocate once its buffers have grown.

mod alloc_support;
mod localizer_sim;
mod matching_support;

use alloc_support::allocations;
use localizer_sim::{commands, mount, ranges, scan, start, walls};
use lrf_lines::{Localizer, LocalizerConfig};
use matching_support::{map_of, Rng};
use nalgebra::Matrix3;

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
    let before = allocations();
    for _ in 0..10 {
        localizer.predict_wheels(&cmd).unwrap();
        localizer.update_compass(0.0).unwrap();
        let report = localizer.update_scan(&scan).unwrap();
        assert!(report.fused > 0);
    }
    assert_eq!(allocations(), before);
}
