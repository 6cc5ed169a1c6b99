//! Line extraction on ray-cast scans of a furnished 9 × 7 m room (two pillars, a table,
//! a cabinet, a sofa, chair legs) with σ_ρ = 10 mm: 361 beams (0.5°) and 721 beams
//! (0.25°) over 180°, default (SICK LMS 2xx) parameters. Target: ≤ 20 µs for 721 beams.

#[path = "../tests/extraction_support/mod.rs"]
mod extraction_support;

use criterion::{criterion_group, criterion_main, Criterion};
use extraction_support::{furnished_room, simulate, Rng, Scanner};
use lrf_lines::{ExtractionParams, LineExtractor};
use std::hint::black_box;

fn extraction(c: &mut Criterion) {
    let room = furnished_room();
    let mut group = c.benchmark_group("extract");
    for (beams, step_deg) in [(361, 0.5_f64), (721, 0.25)] {
        let scanner = Scanner::new(180_f64.to_radians(), step_deg.to_radians());
        assert_eq!(scanner.beams, beams);
        let ranges = simulate(
            &room.walls,
            &room.pose,
            &scanner,
            0.01,
            0.0,
            &mut Rng::new(7),
        );
        let scan = scanner.scan(&ranges);
        let mut extractor = LineExtractor::new(ExtractionParams::default()).unwrap();
        let mut lines = Vec::new();
        extractor.extract(&scan, &mut lines).unwrap();
        assert!(lines.len() >= 8, "{} lines", lines.len());
        group.bench_function(format!("{beams}_beams_{}_lines", lines.len()), |b| {
            b.iter(|| {
                extractor.extract(black_box(&scan), &mut lines).unwrap();
                black_box(lines.len())
            })
        });
    }
    group.finish();
}

criterion_group!(benches, extraction);
criterion_main!(benches);
