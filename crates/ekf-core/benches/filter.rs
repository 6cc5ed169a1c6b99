//! Criterion benchmarks of the filter steps (docs/ARCHITECTURE.md §6 target: predict + compass + 4
//! lines ≤ 1 µs). Run: `cargo bench -p ekf-core --bench filter`.

use core::f64::consts::{FRAC_PI_2, PI};
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use ekf_core::{
    ChiSquareGate, Compass, DiffDrive, Ekf, LaserLine, Line, Pose2, Real, WheelNoise, WheelSpeeds,
};
use nalgebra::{Matrix2, Matrix3};
use std::hint::black_box;

/// A filter in a 10 m × 6 m room, with four matched walls seen by a laser on the robot.
struct Fixture<T: Real> {
    ekf: Ekf<T>,
    robot: DiffDrive<T>,
    noise: WheelNoise<T>,
    speeds: WheelSpeeds<T>,
    compass: Compass<T>,
    lines: [LaserLine<T>; 4],
    gate1: ChiSquareGate<T>,
    gate2: ChiSquareGate<T>,
}

fn fixture<T: Real>() -> Fixture<T> {
    let c = T::lit;
    let pose = Pose2::new(c(4.0), c(2.5), c(0.3));
    let mount = Pose2::new(c(0.2), c(0.0), c(-FRAC_PI_2));
    let walls = [(0.5, PI), (10.0, 0.0), (0.5, -FRAC_PI_2), (6.0, FRAC_PI_2)];
    let lines = walls.map(|(rho, beta)| {
        let wall = Line::new(c(rho), c(beta)).unwrap();
        let seen = wall.to_frame(&pose.compose(&mount));
        let seen = Line::new(seen.rho + c(0.01), seen.beta - c(0.002)).unwrap();
        LaserLine::new(
            seen,
            Matrix2::new(c(4e-4), c(1e-5), c(1e-5), c(2e-4)),
            wall,
            mount,
        )
        .unwrap()
    });
    Fixture {
        ekf: Ekf::new(pose, Matrix3::from_diagonal_element(c(1e-3))).unwrap(),
        robot: DiffDrive::paper(),
        noise: WheelNoise::default(),
        speeds: WheelSpeeds::new(c(3.0), c(3.2), c(0.1)).unwrap(),
        compass: Compass::new(c(0.31), c(1e-3)).unwrap(),
        lines,
        gate1: ChiSquareGate::from_probability(0.99, 1).unwrap(),
        gate2: ChiSquareGate::from_probability(0.99, 2).unwrap(),
    }
}

fn bench_type<T: Real>(c: &mut Criterion, name: &str) {
    let f = fixture::<T>();
    let mut g = c.benchmark_group("ekf");
    g.bench_function(BenchmarkId::new("predict", name), |b| {
        b.iter(|| {
            let mut e = f.ekf;
            e.predict_wheels(&f.robot, black_box(&f.speeds), &f.noise)
                .unwrap();
            e
        })
    });
    g.bench_function(BenchmarkId::new("compass_update", name), |b| {
        b.iter(|| {
            let mut e = f.ekf;
            e.update(black_box(&f.compass), Some(&f.gate1)).unwrap();
            e
        })
    });
    g.bench_function(BenchmarkId::new("four_line_update", name), |b| {
        b.iter(|| {
            let mut e = f.ekf;
            for l in black_box(&f.lines) {
                e.update(l, Some(&f.gate2)).unwrap();
            }
            e
        })
    });
    g.bench_function(BenchmarkId::new("predict_compass_4_lines", name), |b| {
        b.iter(|| {
            let mut e = f.ekf;
            e.predict_wheels(&f.robot, black_box(&f.speeds), &f.noise)
                .unwrap();
            e.update(black_box(&f.compass), Some(&f.gate1)).unwrap();
            for l in black_box(&f.lines) {
                e.update(l, Some(&f.gate2)).unwrap();
            }
            e
        })
    });
    g.finish();
}

fn benches(c: &mut Criterion) {
    bench_type::<f64>(c, "f64");
    bench_type::<f32>(c, "f32");
}

criterion_group!(filter, benches);
criterion_main!(filter);
