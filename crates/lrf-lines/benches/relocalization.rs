//! The relocalization search ([`lrf_lines::relocalize`]) over a 500-segment map: the
//! bundled ACES building map (268 walls) plus 232 of its walls again 1 km away, with the
//! walls within 8 m of a pose in the building seen as the scan's lines. A candidate's
//! window during a verification, a local search (a 3 m window, as after a motion gap)
//! and a search of the whole map.

use criterion::{criterion_group, criterion_main, Criterion};
use ekf_core::Pose2;
use lrf_lines::{
    relocalize, HeadingWindow, LineMap, MapSegment, ObservedLine, RelocalizeParams, SearchWindow,
};
use nalgebra::{Matrix2, Point2};
use std::hint::black_box;

fn map_of_500() -> LineMap {
    let aces = LineMap::from_json_bytes(include_bytes!("../../../testdata/aces-map.json")).unwrap();
    let mut segments = aces.segments.clone();
    let far = |p: &Point2<f64>| Point2::new(p.x + 1000.0, p.y + 1000.0);
    for s in aces.segments.iter().take(500 - aces.segments.len()) {
        segments.push(MapSegment::from_points(far(&s.start), far(&s.end)).unwrap());
    }
    LineMap::new(segments)
}

/// The walls within `reach` of `robot` as lines seen by a laser at the robot's centre.
fn seen(map: &LineMap, robot: &Pose2<f64>, reach: f64) -> Vec<ObservedLine> {
    map.segments
        .iter()
        .filter(|w| {
            let c = nalgebra::center(&w.start, &w.end);
            (c - Point2::new(robot.x, robot.y)).norm() < reach
        })
        .map(|w| {
            let (a, b) = (
                robot.inverse_transform_point(&w.start),
                robot.inverse_transform_point(&w.end),
            );
            ObservedLine {
                line: ekf_core::Line::from_segment(&a, &b).unwrap(),
                covariance: Matrix2::identity() * 1e-4,
                start: a,
                end: b,
                num_points: 40,
            }
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let map = map_of_500();
    assert_eq!(map.len(), 500);
    // A pose of the ACES reference trajectory (scan 100).
    let w = &map.segments[100];
    let mid = nalgebra::center(&w.start, &w.end);
    let robot = Pose2::new(
        mid.x + 0.6 * w.line.beta.cos(),
        mid.y + 0.6 * w.line.beta.sin(),
        0.4,
    );
    let lines = seen(&map, &robot, 8.0);
    let params = RelocalizeParams::default();
    let mount = Pose2::identity();
    let local = SearchWindow::around(Point2::new(robot.x + 1.0, robot.y - 0.5), 3.0);
    // What a verification looks at for one candidate (ekf-fusion's verification.rs): its
    // 99 % bounds after a scan interval of motion, 0.5 m and 8° around a pose off by
    // 0.2 m and 3°.
    let candidate = SearchWindow {
        center: Point2::new(robot.x + 0.2, robot.y),
        radius: 0.5,
        heading: Some(HeadingWindow {
            theta: robot.theta + 3f64.to_radians(),
            tolerance: 8f64.to_radians(),
        }),
    };
    for (name, window) in [
        ("relocalize candidate 0.5 m 8 deg, 500 walls", candidate),
        ("relocalize local 3 m, 500 walls", local),
        ("relocalize global, 500 walls", SearchWindow::global()),
    ] {
        let found = relocalize(&lines, &map, &mount, &window, &params).expect("a pose");
        assert!(found.best.inliers >= 3, "{found:?}");
        c.bench_function(name, |b| {
            b.iter(|| {
                black_box(relocalize(
                    black_box(&lines),
                    &map,
                    &mount,
                    &window,
                    &params,
                ))
            })
        });
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
