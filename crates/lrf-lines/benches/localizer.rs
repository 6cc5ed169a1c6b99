//! The whole scan step, `Localizer::update_scan` (extract → match → update → walls the
//! lines missed), on a 721-beam scan of the simulated room, with a given map (with and
//! without the last step) and with a first-scan map.

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

/// Benchmarks `update_scan` on the scan `localizer` has just been given once.
fn bench_scan(c: &mut Criterion, name: &str, mut localizer: Localizer) {
    let r = ranges(&start(), &walls(), &mut Rng::new(5));
    let scan = scan(&r);
    localizer.update_scan(&scan).unwrap();
    let report = localizer.update_scan(&scan).unwrap();
    assert!(
        report.fused >= 3,
        "the benchmark must fuse lines: {report:?}"
    );
    c.bench_function(name, |b| {
        b.iter(|| black_box(localizer.update_scan(black_box(&scan)).unwrap()))
    });
}

fn bench(c: &mut Criterion) {
    let config = LocalizerConfig {
        laser_mount: mount(),
        ..LocalizerConfig::default()
    };
    let p0 = Matrix3::identity() * 1e-4;
    let given = Localizer::new(config.clone(), start(), p0, map_of(&walls())).unwrap();
    bench_scan(c, "update_scan 721 beams", given);
    // The same without step 4, the walls the lines missed fitted from the points: its cost.
    let mut lines_only = config.clone();
    lines_only.matching.refit_missed_walls = false;
    let given = Localizer::new(lines_only, start(), p0, map_of(&walls())).unwrap();
    bench_scan(c, "update_scan 721 beams, lines only", given);
    // The map's own errors carried in the filter (considered fit, estimated placement).
    let first_scan = Localizer::with_first_scan_map(config, start(), p0).unwrap();
    bench_scan(c, "update_scan 721 beams, first-scan map", first_scan);
}

criterion_group!(benches, bench);
criterion_main!(benches);
