//! Line maps: the first-scan map, fusing a whole run, and the JSON file format.

mod matching_support;

use ekf_core::{angle_diff, Pose2};
use lrf_lines::map::{line_direction, MapFormatErrorKind};
use lrf_lines::{LineMap, MapBuilderParams, MapSegment};
use matching_support::{observe_all, observe_part, rect_room, Rng, Wall, NOISE};
use nalgebra::Point2;
use proptest::prelude::*;
use std::f64::consts::{FRAC_PI_2, PI};

/// The laser 20 cm ahead of the robot centre, 0° to the robot's right (SICK-style).
fn mount() -> Pose2<f64> {
    Pose2::new(0.2, 0.0, -FRAC_PI_2)
}

/// The room `[−1, 5] × [−1, 3]` and its walls' world `(ρ, β)`, in `rect_room` order.
fn room() -> (Vec<Wall>, [(f64, f64); 4]) {
    (
        rect_room(-1.0, -1.0, 5.0, 3.0),
        [(1.0, -FRAC_PI_2), (5.0, 0.0), (3.0, FRAC_PI_2), (1.0, PI)],
    )
}

/// `true` if `s` spans `wall` (its ends, in either order) within `tol`.
fn same_ends(s: &MapSegment, wall: &Wall, tol: f64) -> bool {
    let d = |a: &Point2<f64>, b: &Point2<f64>| (a - b).norm();
    (d(&s.start, &wall.0) < tol && d(&s.end, &wall.1) < tol)
        || (d(&s.start, &wall.1) < tol && d(&s.end, &wall.0) < tol)
}

#[test]
fn first_scan_map_of_a_rectangle_room_has_its_four_walls() {
    let (walls, expected) = room();
    let sensor = Pose2::new(1.0, 0.5, 0.3).compose(&mount());
    let map = LineMap::from_scan(&observe_all(&walls, &sensor, NOISE), &sensor).unwrap();
    assert_eq!(map.len(), 4);
    assert_eq!(map.frame_id, "map");
    for ((segment, wall), (rho, beta)) in map.segments.iter().zip(&walls).zip(expected) {
        assert!((segment.line.rho - rho).abs() < 1e-9, "{segment:?}");
        assert!(
            angle_diff(segment.line.beta, beta).abs() < 1e-9,
            "{segment:?}"
        );
        assert!(same_ends(segment, wall, 1e-9), "{segment:?} vs {wall:?}");
    }
    assert!(LineMap::from_scan(&[], &Pose2::new(f64::NAN, 0.0, 0.0)).is_err());
}

#[test]
fn a_run_of_noisy_partial_sightings_fuses_into_one_segment_per_wall() {
    let (walls, expected) = room();
    let mut rng = Rng::new(7);
    let mut scans = Vec::new();
    // Per wall, the union [min f0, max f1] of the parts seen.
    let mut union = [(1.0_f64, 0.0_f64); 4];
    for k in 0..12 {
        let t = f64::from(k) / 12.0;
        let robot = Pose2::new(0.5 + 3.0 * t, 0.2 + 1.5 * t, 2.0 * PI * t);
        let sensor = robot.compose(&mount());
        let mut lines = Vec::new();
        for (w, wall) in walls.iter().enumerate() {
            let f0 = 0.45 * rng.uniform();
            let f1 = 1.0 - 0.45 * rng.uniform();
            union[w] = (union[w].0.min(f0), union[w].1.max(f1));
            lines.push(observe_part(wall, f0, f1, &sensor, NOISE, Some(&mut rng)));
        }
        // A phantom (a person) seen once, in the middle of the room.
        if k == 5 {
            let phantom = (Point2::new(2.0, 1.0), Point2::new(2.3, 1.4));
            lines.push(observe_part(&phantom, 0.0, 1.0, &sensor, NOISE, None));
        }
        scans.push((lines, sensor));
    }
    let run = || scans.iter().map(|(l, p)| (l.as_slice(), *p));
    let params = MapBuilderParams {
        min_sightings: 2,
        ..MapBuilderParams::default()
    };
    let map = LineMap::from_run(run(), &params).unwrap();
    assert_eq!(map.len(), 4, "{map:#?}");
    for (w, (wall, (rho, beta))) in walls.iter().zip(expected).enumerate() {
        let s = map
            .segments
            .iter()
            .find(|s| angle_diff(s.line.beta, beta).abs() < 0.01)
            .unwrap();
        assert!((s.line.rho - rho).abs() < 0.01, "wall {w}: {s:?}");
        // Extent: the union of the parts seen, along the wall.
        let d = line_direction(&s.line);
        let along = |p: &Point2<f64>| p.coords.dot(&d);
        let len = (wall.1 - wall.0).norm();
        let (u0, u1) = (
            along(&(wall.0 + (wall.1 - wall.0) * union[w].0)),
            along(&(wall.0 + (wall.1 - wall.0) * union[w].1)),
        );
        let (want_lo, want_hi) = (u0.min(u1), u0.max(u1));
        let (lo, hi) = s.extent_along(&s.line);
        assert!(
            (lo - want_lo).abs() < 0.05 && (hi - want_hi).abs() < 0.05,
            "wall {w} (length {len}): extent [{lo}, {hi}], union [{want_lo}, {want_hi}]"
        );
    }
    // Keeping walls seen once keeps the phantom too.
    let all = LineMap::from_run(run(), &MapBuilderParams::default()).unwrap();
    assert_eq!(all.len(), 5);
}

#[test]
fn collinear_pieces_join_across_small_gaps_only() {
    let sensor = Pose2::new(0.0, 0.0, 0.0);
    let wall: Wall = (Point2::new(3.0, -2.0), Point2::new(3.0, 6.0));
    // Pieces [0, 0.4] and [0.45, 1.0] of an 8 m wall: a 0.4 m gap, above max_gap 0.3.
    let a = observe_part(&wall, 0.0, 0.4, &sensor, NOISE, None);
    let b = observe_part(&wall, 0.45, 1.0, &sensor, NOISE, None);
    let params = MapBuilderParams::default();
    let two = LineMap::from_run([(&[a, b][..], sensor)], &params).unwrap();
    assert_eq!(two.len(), 2);
    // A later sighting of the middle bridges them: finish() merges into one wall.
    let middle = observe_part(&wall, 0.3, 0.5, &sensor, NOISE, None);
    let one = LineMap::from_run([(&[a, b][..], sensor), (&[middle][..], sensor)], &params).unwrap();
    assert_eq!(one.len(), 1);
    assert!(
        same_ends(&one.segments[0], &wall, 1e-9),
        "{:?}",
        one.segments[0]
    );
}

fn awkward_map() -> LineMap {
    let p = Point2::new;
    let mut map = LineMap::new(vec![
        MapSegment::from_points(p(0.1 + 0.2, 1.0 / 3.0), p(-123.456789012345, 1e-7)).unwrap(),
        MapSegment::from_points(p(5e-324, -0.0), p(1e300, 2.0_f64.sqrt())).unwrap(),
        MapSegment::from_points(p(-1.0, -1.0), p(5.0, -1.0)).unwrap(),
    ]);
    map.frame_id = "odom \"quoted\"".into();
    map
}

#[test]
fn json_round_trip_is_exact() {
    let map = awkward_map();
    let text = map.to_json().unwrap();
    let back = LineMap::from_json(&text).unwrap();
    assert_eq!(back, map);
    assert_eq!(back.to_json().unwrap(), text);
    assert_eq!(
        LineMap::from_json(&LineMap::default().to_json().unwrap()).unwrap(),
        LineMap::default()
    );
}

#[test]
fn the_documented_example_loads() {
    let text = r#"{
  "format": "ekf-loc line map",
  "version": 1,
  "frame_id": "map",
  "segments": [
    {"start": [-1.0, -1.0], "end": [5.0, -1.0]},
    {"start": [5.0, -1.0], "end": [5.0, 3.0]}
  ]
}"#;
    let map = LineMap::from_json(text).unwrap();
    assert_eq!(map.len(), 2);
    assert!((map.segments[1].line.rho - 5.0).abs() < 1e-12);
    // frame_id is optional.
    let map = LineMap::from_json(r#"{"format": "ekf-loc line map", "version": 1, "segments": []}"#)
        .unwrap();
    assert_eq!(map.frame_id, "map");
}

/// The error for `text`, its message, and a check that the message names `needles`.
fn load_error(text: &str, needles: &[&str]) -> lrf_lines::MapFormatError {
    let e = LineMap::from_json(text).unwrap_err();
    let msg = e.to_string();
    for n in needles {
        assert!(msg.contains(n), "{msg:?} should contain {n:?}");
    }
    e
}

fn file(segments: &str) -> String {
    format!("{{\"format\": \"ekf-loc line map\", \"version\": 1, \"segments\": [\n{segments}\n]}}")
}

const GOOD: &str = r#"{"start": [0, 0], "end": [1, 0]}"#;

#[test]
fn malformed_files_name_the_entry_and_field() {
    // Not JSON: truncated inside segment 1's end point.
    let e = load_error(
        &file(&format!("{GOOD},\n{{\"start\": [0, 1], \"end\": [2,")),
        &["segments[1].end", "line"],
    );
    assert!(matches!(e.kind, MapFormatErrorKind::Syntax { .. }));
    assert_eq!(e.segment, Some(1));
    // Missing end.
    let e = load_error(
        &file(&format!("{GOOD},\n{{\"start\": [0, 1]}}")),
        &["segments[1]", "missing field `end`"],
    );
    assert_eq!(e.kind, MapFormatErrorKind::MissingField { field: "end" });
    // NaN is not JSON; the error still names the coordinate.
    let e = load_error(
        &file(&format!(
            "{GOOD},\n{GOOD},\n{{\"start\": [NaN, 1], \"end\": [2, 1]}}"
        )),
        &["segments[2].start[0]"],
    );
    assert_eq!(e.segment, Some(2));
    // null where a number belongs.
    load_error(
        &file(r#"{"start": [0, null], "end": [2, 1]}"#),
        &[
            "segments[0].start[1]",
            "expected a finite number, found null",
        ],
    );
    // Too large for f64.
    load_error(
        &file(r#"{"start": [0, 1], "end": [1e999, 1]}"#),
        &["segments[0].end[0]"],
    );
    // Zero length.
    let e = load_error(
        &file(&format!("{GOOD},\n{{\"start\": [2, 1], \"end\": [2, 1]}}")),
        &["segments[1]", "zero-length", "`start`", "`end`"],
    );
    assert_eq!(e.kind, MapFormatErrorKind::ZeroLength);
    // A point with three coordinates.
    load_error(
        &file(r#"{"start": [0, 1, 2], "end": [2, 1]}"#),
        &["segments[0].start", "[x, y]", "array of 3"],
    );
    // A typo in a field name.
    load_error(
        &file(r#"{"start": [0, 1], "edn": [2, 1]}"#),
        &["segments[0]", "unknown field `edn`"],
    );
    // Wrong version and format.
    let text = file(GOOD).replace("\"version\": 1", "\"version\": 2");
    load_error(&text, &["version", "expected 1", "found the number 2"]);
    let text = file(GOOD).replace("ekf-loc line map", "ekf-loc point map");
    load_error(&text, &["format", "\"ekf-loc point map\""]);
    load_error(
        r#"{"version": 1, "segments": []}"#,
        &["missing field `format`"],
    );
    load_error("[1, 2]", &["map file", "expected an object"]);
    load_error("", &["invalid JSON"]);
    assert!(LineMap::from_json_bytes(b"{\"format\": \"\xff\"}").is_err());
}

#[test]
fn saving_refuses_what_loading_would() {
    let mut map = awkward_map();
    map.segments[1].end.y = f64::NAN;
    assert!(map
        .to_json()
        .unwrap_err()
        .to_string()
        .contains("segments[1].end[1]"));
    map.segments[1].end = map.segments[1].start;
    assert_eq!(map.to_json().unwrap_err().segment, Some(1));
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    #[test]
    fn loading_random_bytes_never_panics(bytes in proptest::collection::vec(any::<u8>(), 0..300)) {
        let _ = LineMap::from_json_bytes(&bytes);
    }

    #[test]
    fn loading_a_damaged_file_never_panics(cut in 0usize..400, pos in 0usize..400, byte in any::<u8>()) {
        let mut bytes = awkward_map().to_json().unwrap().into_bytes();
        let pos = pos.min(bytes.len() - 1);
        bytes[pos] = byte;
        bytes.truncate(cut.max(1));
        if let Err(e) = LineMap::from_json_bytes(&bytes) {
            prop_assert!(!e.to_string().is_empty());
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(100))]

    #[test]
    fn building_a_map_from_random_sightings_never_panics(
        scans in proptest::collection::vec(
            (
                (-5.0..5.0, -5.0..5.0, -PI..PI),
                proptest::collection::vec((0.0..8.0, -PI..PI, -8.0..8.0, -8.0..8.0, -8.0..8.0, -8.0..8.0), 0..8),
            ),
            0..6,
        ),
        max_gap in 0.0..1.0,
    ) {
        let scans: Vec<(Vec<lrf_lines::ObservedLine>, Pose2<f64>)> = scans
            .into_iter()
            .map(|((x, y, t), lines)| {
                let lines = lines
                    .into_iter()
                    .map(|(r, psi, x0, y0, x1, y1)| {
                        let line = ekf_core::Line::new(r, psi).unwrap();
                        lrf_lines::ObservedLine {
                            line,
                            covariance: nalgebra::Matrix2::new(1e-4, 0.0, 0.0, 1e-4),
                            start: line.project(&Point2::new(x0, y0)),
                            end: line.project(&Point2::new(x1, y1)),
                            num_points: 10,
                        }
                    })
                    .collect();
                (lines, Pose2::new(x, y, t))
            })
            .collect();
        let params = MapBuilderParams { max_gap, ..MapBuilderParams::default() };
        let map = LineMap::from_run(scans.iter().map(|(l, p)| (l.as_slice(), *p)), &params).unwrap();
        let total: usize = scans.iter().map(|(l, _)| l.len()).sum();
        prop_assert!(map.len() <= total);
        // Whatever was built can be saved and loaded back unchanged.
        prop_assert_eq!(LineMap::from_json(&map.to_json().unwrap()).unwrap(), map);
    }
}

#[test]
fn a_long_corridor_gives_one_wall_per_piece_between_doors() {
    // 200 m of corridor, a 1 m door every 4 m on both sides, scans every 0.2 m seeing the
    // pieces within 8 m: the walls spread over many cells of the builder's index, and each
    // piece must still come out once, with its extent.
    let mut rng = Rng::new(3);
    let pieces = |x: f64| {
        let first = ((x - 8.0) / 4.0).floor().max(0.0) as i64;
        let last = (((x + 8.0) / 4.0).ceil() as i64).min(50);
        (first..last).flat_map(|i| {
            let x0 = 4.0 * i as f64;
            [-1.5, 1.5].map(|y| -> Wall { (Point2::new(x0, y), Point2::new(x0 + 3.0, y)) })
        })
    };
    let scans: Vec<_> = (0..1000)
        .map(|k| {
            let sensor = Pose2::new(0.2 * f64::from(k), 0.0, 0.0);
            let lines: Vec<_> = pieces(sensor.x)
                .map(|w| observe_part(&w, 0.0, 1.0, &sensor, NOISE, Some(&mut rng)))
                .collect();
            (lines, sensor)
        })
        .collect();
    let map = LineMap::from_run(
        scans.iter().map(|(l, p)| (l.as_slice(), *p)),
        &MapBuilderParams::default(),
    )
    .unwrap();
    assert_eq!(map.len(), 100);
    for s in &map.segments {
        let (lo, hi) = (s.start.x.min(s.end.x), s.start.x.max(s.end.x));
        let x0 = 4.0 * (lo / 4.0).round();
        assert!(
            (s.start.y.abs() - 1.5).abs() < 0.01 && (s.end.y.abs() - 1.5).abs() < 0.01,
            "{s:?}"
        );
        assert!(
            (lo - x0).abs() < 0.05 && (hi - (x0 + 3.0)).abs() < 0.05,
            "{s:?}"
        );
    }
}
