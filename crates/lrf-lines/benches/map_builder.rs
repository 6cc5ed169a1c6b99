//! Building a map from runs of two lengths along an endless corridor with a door every
//! 4 m on both sides, so the map grows with the run: the cost per scan must not grow with
//! it (`map build --from-truth` on long logs was quadratic before the wall index).

#[path = "../tests/matching_support/mod.rs"]
mod matching_support;

use criterion::{criterion_group, criterion_main, Criterion};
use ekf_core::Pose2;
use lrf_lines::{MapBuilder, MapBuilderParams, ObservedLine};
use matching_support::{observe_part, Rng, Wall, NOISE};
use nalgebra::Point2;
use std::hint::black_box;

/// Scans every 0.2 m along the corridor, each seeing the wall pieces within 8 m.
fn corridor_run(scans: usize) -> Vec<(Vec<ObservedLine>, Pose2<f64>)> {
    let mut rng = Rng::new(7);
    (0..scans)
        .map(|k| {
            let x = 0.2 * k as f64;
            let sensor = Pose2::new(x, 0.0, 0.0);
            let first = ((x - 8.0) / 4.0).floor().max(0.0) as i64;
            let last = ((x + 8.0) / 4.0).ceil() as i64;
            let lines = (first..last)
                .flat_map(|i| {
                    let x0 = 4.0 * i as f64;
                    [-1.5, 1.5].map(|y| -> Wall { (Point2::new(x0, y), Point2::new(x0 + 3.0, y)) })
                })
                .map(|wall| observe_part(&wall, 0.0, 1.0, &sensor, NOISE, Some(&mut rng)))
                .collect();
            (lines, sensor)
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    for scans in [1_000, 8_000] {
        let run = corridor_run(scans);
        c.bench_function(&format!("map builder, {scans}-scan corridor"), |b| {
            b.iter(|| {
                let mut builder = MapBuilder::new(MapBuilderParams::default()).unwrap();
                for (lines, pose) in &run {
                    builder.add_scan(black_box(lines), pose).unwrap();
                }
                builder.finish()
            })
        });
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(10);
    targets = bench
}
criterion_main!(benches);
