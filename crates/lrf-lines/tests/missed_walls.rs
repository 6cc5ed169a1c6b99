//! What the scan update takes from the scan beyond its lines: pieces of one wall fitted
//! together (step 3, `ScanReport::merged`), and walls the line extraction missed, fitted
//! from the scan points that lie on them (step 4, `refit_missed_walls`).

mod matching_support;

use ekf_core::Pose2;
use lrf_lines::{LaserScan, LineMap, Localizer, LocalizerConfig, RejectReason, ScanReport};
use matching_support::{map_of, ray_cast, Beams, Wall};
use nalgebra::{Matrix3, Point2, Vector3};

/// A corridor along x: the end wall at x = 3, the walls at y = 2 and y = −2.
fn corridor() -> Vec<Wall> {
    vec![
        (Point2::new(3.0, -2.5), Point2::new(3.0, 2.5)),
        (Point2::new(-2.0, 2.0), Point2::new(3.0, 2.0)),
        (Point2::new(-2.0, -2.0), Point2::new(3.0, -2.0)),
    ]
}

/// 181 beams, 1° apart, from −90° to 90°.
const BEAMS: Beams = Beams {
    angle_min: -std::f64::consts::FRAC_PI_2,
    increment: std::f64::consts::PI / 180.0,
    count: 181,
    range_max: 10.0,
};

/// The exact ranges from the origin (laser at the robot's origin), with the wall at
/// y = −2 seen only in pieces of `piece` beams, each followed by as many without return:
/// too few points each for the extraction's six.
fn ranges(piece: usize) -> Vec<f32> {
    let mut r = ray_cast(&corridor(), &Pose2::identity(), &BEAMS, 0.0, None);
    for (i, range) in r.iter_mut().enumerate() {
        let bearing = BEAMS.angle_min + i as f64 * BEAMS.increment;
        // The wall at y = −2 is what the beams between −90° and −34° meet first.
        if bearing < (-2.0_f64).atan2(3.0) && (i / piece) % 2 == 1 {
            *range = f32::INFINITY;
        }
    }
    r
}

fn scan(ranges: &[f32]) -> LaserScan<'_> {
    scan_of(&BEAMS, ranges)
}

fn scan_of<'a>(beams: &Beams, ranges: &'a [f32]) -> LaserScan<'a> {
    LaserScan {
        angle_min: beams.angle_min,
        angle_increment: beams.increment,
        range_min: 0.05,
        range_max: beams.range_max,
        ranges,
    }
}

/// One scan update from (0, 0.03, 0) with σ = 0.1 m, 2°, against `map`; the true pose is
/// the origin.
fn update(map: LineMap, ranges: &[f32], refit: bool) -> (ScanReport, Localizer) {
    update_with(map, &scan(ranges), refit)
}

fn update_with(map: LineMap, scan: &LaserScan<'_>, refit: bool) -> (ScanReport, Localizer) {
    let mut config = LocalizerConfig::default();
    config.matching.refit_missed_walls = refit;
    let p = Matrix3::from_diagonal(&Vector3::new(0.01, 0.01, 2.0_f64.to_radians().powi(2)));
    let mut localizer = Localizer::new(config, Pose2::new(0.0, 0.03, 0.0), p, map).unwrap();
    let report = localizer.update_scan(scan).unwrap();
    (report, localizer)
}

#[test]
fn a_wall_seen_only_in_short_pieces_is_fitted_from_them_and_fused() {
    let ranges = ranges(4);
    let (without, before) = update(map_of(&corridor()), &ranges, false);
    let (with, after) = update(map_of(&corridor()), &ranges, true);
    // The end wall and the wall at y = 2 are lines; the pieces of y = −2 are not.
    assert_eq!(
        (without.extracted, without.fused, without.refitted),
        (2, 2, 0)
    );
    assert_eq!((with.extracted, with.fused, with.refitted), (2, 2, 1));
    // The second wall along y halves (about) the lateral variance, and the estimate is
    // within 3σ of the truth.
    let (var_before, var_after) = (before.covariance()[(1, 1)], after.covariance()[(1, 1)]);
    assert!(var_after < 0.75 * var_before, "{var_after} vs {var_before}");
    assert!(
        after.pose().y.abs() < 3.0 * var_after.sqrt(),
        "{:?}",
        after.pose()
    );
    let p = after.covariance();
    assert!((p - p.transpose()).abs().max() <= 1e-12 && p.cholesky().is_some());
}

#[test]
fn points_off_every_wall_are_not_forced_onto_one() {
    // The map's wall is 0.4 m from where the laser sees it: about 10σ, so no beam's point
    // lies on it.
    let mut walls = corridor();
    walls[2] = (Point2::new(-2.0, -2.4), Point2::new(3.0, -2.4));
    let (report, _) = update(map_of(&walls), &ranges(4), true);
    assert_eq!((report.extracted, report.fused, report.refitted), (2, 2, 0));
}

#[test]
fn pieces_of_fewer_than_three_beams_are_not_a_wall() {
    let (report, _) = update(map_of(&corridor()), &ranges(2), true);
    assert_eq!((report.fused, report.refitted), (2, 0));
}

#[test]
fn without_two_fused_lines_nothing_is_refitted() {
    // Only the end wall is a line: one fused line does not confirm the pose enough to
    // trust where the other points fall.
    let walls = [corridor()[0], corridor()[2]];
    let mut ranges = ray_cast(&walls, &Pose2::identity(), &BEAMS, 0.0, None);
    let pieces = self::ranges(4);
    for (r, p) in ranges.iter_mut().zip(&pieces) {
        if p.is_infinite() {
            *r = f32::INFINITY;
        }
    }
    let (report, _) = update(map_of(&walls), &ranges, true);
    assert_eq!((report.extracted, report.fused, report.refitted), (1, 1, 0));
}

#[test]
fn a_wall_across_the_seam_of_a_scan_all_round_is_one_wall() {
    // A room 5 m by 4 m around the origin, seen all round: beam i looks at (i − 180)°, so
    // beams 359 (179°) and 0 (−180°) are beside each other on the wall behind, x = −2.
    let beams = Beams {
        angle_min: -std::f64::consts::PI,
        increment: std::f64::consts::PI / 180.0,
        count: 360,
        range_max: 10.0,
    };
    let mut room = corridor();
    room.push((Point2::new(-2.0, -2.5), Point2::new(-2.0, 2.5)));
    let mut ranges = ray_cast(&room, &Pose2::identity(), &beams, 0.0, None);
    // The wall behind (bearings beyond ±135°) returns on beams 349..=359 (169° to 179°:
    // 0.35 m, too short a line) and on beams 0 and 1 (−180°, −179°: too few for a piece
    // of their own) only; together they span 0.42 m, long enough.
    for (i, r) in ranges.iter_mut().enumerate() {
        let behind = !(45..=315).contains(&i);
        if behind && !(349..360).contains(&i) && i > 1 {
            *r = f32::INFINITY;
        }
    }
    let scan = scan_of(&beams, &ranges);
    let (report, with) = update_with(map_of(&room), &scan, true);
    let (_, without) = update_with(map_of(&room), &scan, false);
    // The front and the two side walls are lines; the wall behind is fitted from the 13
    // beams on both sides of the seam, and it pins x further.
    assert_eq!((report.fused, report.refitted), (3, 1));
    let (var_with, var_without) = (with.covariance()[(0, 0)], without.covariance()[(0, 0)]);
    assert!(var_with < 0.9 * var_without, "{var_with} vs {var_without}");
}

/// The corridor's ranges with the wall at y = −2 seen in two pieces, the beams between
/// −70° and −50° without return (a door 1 m wide): extraction keeps them two lines.
fn door_ranges() -> Vec<f32> {
    let mut r = ray_cast(&corridor(), &Pose2::identity(), &BEAMS, 0.0, None);
    for (i, range) in r.iter_mut().enumerate() {
        let bearing = (BEAMS.angle_min + i as f64 * BEAMS.increment).to_degrees();
        if bearing > -70.5 && bearing < -49.5 {
            *range = f32::INFINITY;
        }
    }
    r
}

#[test]
fn two_pieces_of_one_wall_are_fused_as_one_line_fitted_to_both() {
    let ranges = door_ranges();
    let (report, merged) = update(map_of(&corridor()), &ranges, false);
    // Four lines, one wall for two of them: one is matched, the other rejected for it,
    // then fitted with it.
    assert_eq!(
        (report.extracted, report.matched, report.rejected),
        (4, 3, 1)
    );
    assert_eq!((report.fused, report.merged), (3, 1));
    // Fusing the lines given without their scan cannot merge: the piece alone is fused.
    let mut config = LocalizerConfig::default();
    config.matching.refit_missed_walls = false;
    let p = Matrix3::from_diagonal(&Vector3::new(0.01, 0.01, 2.0_f64.to_radians().powi(2)));
    let mut alone =
        Localizer::new(config, Pose2::new(0.0, 0.03, 0.0), p, map_of(&corridor())).unwrap();
    let lines = merged.last_lines().to_vec();
    let report = alone.update_lines(&lines).unwrap();
    assert_eq!((report.fused, report.merged), (3, 0));
    // The longer baseline pins the heading better than the one piece does.
    let (var_merged, var_alone) = (merged.covariance()[(2, 2)], alone.covariance()[(2, 2)]);
    assert!(var_merged < var_alone, "{var_merged} vs {var_alone}");
    assert!(merged.pose().y.abs() < 3.0 * merged.covariance()[(1, 1)].sqrt());
}

#[test]
fn pieces_that_are_not_one_straight_wall_are_not_merged() {
    // Past the door the wall is 0.1 m farther out (y = −2.1): both pieces still gate
    // with the map's wall at y = −2, but their points are not one line.
    let mut offset = corridor();
    offset[2] = (Point2::new(-2.0, -2.1), Point2::new(3.0, -2.1));
    let farther = ray_cast(&offset, &Pose2::identity(), &BEAMS, 0.0, None);
    let mut ranges = door_ranges();
    for (i, r) in ranges.iter_mut().enumerate() {
        let bearing = (BEAMS.angle_min + i as f64 * BEAMS.increment).to_degrees();
        if (-49.5..-33.0).contains(&bearing) {
            *r = farther[i];
        }
    }
    let (report, localizer) = update(map_of(&corridor()), &ranges, false);
    assert_eq!((report.extracted, report.rejected), (4, 1));
    // Rejected because its wall went to the other piece: the merge was considered, and
    // refused.
    let matched = localizer.last_matches().matches();
    let rejection = localizer.last_matches().rejections()[0];
    assert!(
        matches!(rejection.reason, RejectReason::MapLineTaken { map: 2, by }
            if matched.iter().any(|m| m.observed == by && m.map == 2)),
        "{rejection:?}"
    );
    assert_eq!(report.merged, 0);
}

#[test]
fn a_wall_of_a_first_scan_map_seen_only_in_pieces_is_refitted_with_its_error() {
    // The first scan sees all three walls whole and becomes the map; the second, from
    // the same place, sees the wall at y = −2 only in short pieces.
    let p0 = Matrix3::from_diagonal(&Vector3::new(1e-4, 1e-4, 0.5_f64.to_radians().powi(2)));
    let mut localizer =
        Localizer::with_first_scan_map(LocalizerConfig::default(), Pose2::identity(), p0).unwrap();
    let whole = ray_cast(&corridor(), &Pose2::identity(), &BEAMS, 0.0, None);
    let first = localizer.update_scan(&scan(&whole)).unwrap();
    assert!(first.map_built);
    assert_eq!(localizer.map().len(), 3);
    let before = *localizer.covariance();
    let report = localizer.update_scan(&scan(&ranges(4))).unwrap();
    assert_eq!((report.extracted, report.fused, report.refitted), (2, 2, 1));
    // The map's walls stay where the first scan put them (to within a millimetre: the
    // second scan agrees with it), and the state is still consistent.
    let off_line = |p: &Point2<f64>, (a, b): &Wall| {
        let (e, d) = (b - a, p - a);
        (e.x * d.y - e.y * d.x).abs() / e.norm()
    };
    for wall in &localizer.map().segments {
        assert!(
            corridor()
                .iter()
                .any(|w| off_line(&wall.start, w) < 1e-3 && off_line(&wall.end, w) < 1e-3),
            "{wall:?}"
        );
    }
    let p = localizer.covariance();
    assert!((p - p.transpose()).abs().max() <= 1e-12 && p.cholesky().is_some());
    assert!(p[(1, 1)] <= before[(1, 1)], "{p} vs {before}");
    assert!(localizer.pose().y.abs() < 3.0 * p[(1, 1)].sqrt() + 1e-3);
}
