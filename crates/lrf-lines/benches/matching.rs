//! Matching 20 observed lines against a 50-wall office map.

#[path = "../tests/matching_support/mod.rs"]
mod matching_support;

use criterion::{criterion_group, criterion_main, Criterion};
use ekf_core::{Ekf, Pose2};
use lrf_lines::{MatchParams, MatchResult, Matcher};
use matching_support::{map_of, observe_part, Wall, NOISE};
use nalgebra::{Matrix3, Point2, Vector3};
use std::hint::black_box;

/// 50 walls: a 5 × 5 grid of rooms, 25 horizontal and 25 vertical wall pieces.
fn office() -> Vec<Wall> {
    let mut walls = Vec::new();
    for i in 0..5 {
        for j in 0..5 {
            let (x, y) = (5.0 * f64::from(i), 3.0 * f64::from(j));
            walls.push((Point2::new(x, y), Point2::new(x + 4.0, y)));
            walls.push((Point2::new(x, y + 0.5), Point2::new(x, y + 2.5)));
        }
    }
    walls
}

fn bench(c: &mut Criterion) {
    let walls = office();
    let map = map_of(&walls);
    let truth = Pose2::new(7.3, 4.4, 0.3);
    // The 20 walls closest to the robot, seen whole.
    let mut near = walls.clone();
    let dist = |w: &Wall| (nalgebra::center(&w.0, &w.1) - Point2::new(truth.x, truth.y)).norm();
    near.sort_by(|a, b| dist(a).total_cmp(&dist(b)));
    let observed: Vec<_> = near[..20]
        .iter()
        .map(|w| observe_part(w, 0.0, 1.0, &truth, NOISE, None))
        .collect();
    let believed = Pose2::new(truth.x + 0.05, truth.y - 0.03, truth.theta + 0.02);
    let p = Matrix3::from_diagonal(&Vector3::new(0.01, 0.01, 1e-3));
    let ekf = Ekf::new(believed, p).unwrap();
    let matcher = Matcher::new(MatchParams::default()).unwrap();
    let mut out = MatchResult::new();
    matcher.match_lines(&observed, &map, &ekf, &Pose2::identity(), &mut out);
    assert_eq!(
        out.matches().len(),
        20,
        "the benchmark must match every line"
    );
    c.bench_function("match 20 lines against 50 walls", |b| {
        b.iter(|| {
            matcher.match_lines(
                black_box(&observed),
                black_box(&map),
                black_box(&ekf),
                &Pose2::identity(),
                &mut out,
            );
            black_box(out.matches().len())
        })
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
