//! The whole scan step, `Localizer::update_scan` (extract → match → update), on a
//! 721-beam scan of the simulated room.

#[path = "../tests/localizer_sim/mod.rs"]
mod localizer_sim;
#[path = "../tests/matching_support/mod.rs"]
mod matching_support;

use criterion::{criterion_group, criterion_main, Criterion};
use localizer_sim::{mount, ranges, scan, start, walls};
use lrf_lines::{Localizer, LocalizerConfig};
use matching_support::{map_of, Rng};
use nalgebra::Matrix3;
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let config = LocalizerConfig {
        laser_mount: mount(),
        ..LocalizerConfig::default()
    };
    let walls = walls();
    let mut localizer =
        Localizer::new(config, start(), Matrix3::identity() * 1e-4, map_of(&walls)).unwrap();
    let r = ranges(&start(), &walls, &mut Rng::new(5));
    let scan = scan(&r);
    let report = localizer.update_scan(&scan).unwrap();
    assert!(
        report.fused >= 3,
        "the benchmark must fuse lines: {report:?}"
    );
    c.bench_function("update_scan 721 beams", |b| {
        b.iter(|| black_box(localizer.update_scan(black_box(&scan)).unwrap()))
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
