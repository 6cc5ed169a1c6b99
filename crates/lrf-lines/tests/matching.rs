//! Matching observed lines to map walls: gate, overlap, one wall per line, joint
//! compatibility.

mod matching_support;

use ekf_core::{Ekf, LaserLine, Line, Pose2};
use lrf_lines::{
    LineMap, MapSegment, MatchParams, MatchResult, Matcher, ObservedLine, RejectReason,
};
use matching_support::{map_of, observe_part, rect_room, Wall, NOISE};
use nalgebra::{Matrix2, Matrix3, Point2, Vector3};
use proptest::prelude::*;
use std::collections::HashSet;
use std::f64::consts::{FRAC_PI_2, PI};

fn mount() -> Pose2<f64> {
    Pose2::new(0.2, 0.0, -FRAC_PI_2)
}

/// A filter believing `pose` with standard deviations 0.2 m and 5°.
fn filter_at(pose: Pose2<f64>) -> Ekf<f64> {
    let p = Matrix3::from_diagonal(&Vector3::new(0.04, 0.04, 5.0_f64.to_radians().powi(2)));
    Ekf::new(pose, p).unwrap()
}

fn matcher() -> Matcher {
    Matcher::new(MatchParams::default()).unwrap()
}

/// What the laser at `robot ⊕ mount` sees of the whole of each wall (noise-free).
fn see(walls: &[Wall], robot: &Pose2<f64>) -> Vec<ObservedLine> {
    let sensor = robot.compose(&mount());
    walls
        .iter()
        .map(|w| observe_part(w, 0.0, 1.0, &sensor, NOISE, None))
        .collect()
}

#[test]
fn walls_are_matched_despite_a_pose_offset_and_a_phantom_is_gated_out() {
    // The room plus an inner wall parallel to the right one.
    let mut walls = rect_room(-1.0, -1.0, 5.0, 3.0);
    walls.push((Point2::new(3.5, 1.5), Point2::new(3.5, 2.8)));
    let map = map_of(&walls);
    let truth = Pose2::new(1.5, 0.5, 0.4);
    let mut observed = see(&walls, &truth);
    // A phantom: a diagonal line no wall explains (a person's legs, a chair).
    let phantom = (Point2::new(2.0, -0.5), Point2::new(2.4, 0.0));
    observed.push(observe_part(
        &phantom,
        0.0,
        1.0,
        &truth.compose(&mount()),
        NOISE,
        None,
    ));
    // The filter believes the robot 0.2 m and 3° off.
    let believed = Pose2::new(
        truth.x + 0.12,
        truth.y - 0.16,
        truth.theta + 3.0_f64.to_radians(),
    );
    let mut out = MatchResult::new();
    matcher().match_lines(&observed, &map, &filter_at(believed), &mount(), &mut out);
    assert_eq!(out.matches().len(), walls.len(), "{:#?}", out.rejections());
    for m in out.matches() {
        assert_eq!(m.observed, m.map);
        assert!(m.innovation.nis <= 9.2104 && m.overlap > 0.0);
        // The innovation is ekf-core's, at the predicted state, with the observed line's
        // covariance plus the map noise.
        let model = LaserLine::new(
            observed[m.observed].line,
            matcher()
                .params()
                .line_noise(&observed[m.observed].covariance),
            map.segments[m.map].line,
            mount(),
        )
        .unwrap();
        assert_eq!(
            filter_at(believed).innovation(&model).unwrap().nis,
            m.innovation.nis
        );
    }
    // Matches come in increasing NIS.
    assert!(out
        .matches()
        .windows(2)
        .all(|w| w[0].innovation.nis <= w[1].innovation.nis));
    assert_eq!(out.rejections().len(), 1);
    assert_eq!(out.rejections()[0].observed, walls.len());
    assert_eq!(out.rejections()[0].reason, RejectReason::OutsideGate);
    assert_eq!(out.rejections()[0].reason.to_string(), "outside gate");
}

#[test]
fn parallel_walls_are_told_apart_by_overlap() {
    // A corridor wall at y = 2 for x in [0, 5], and a recessed one at y = 2.3 further on.
    let near: Wall = (Point2::new(0.0, 2.0), Point2::new(5.0, 2.0));
    let far: Wall = (Point2::new(6.0, 2.3), Point2::new(10.0, 2.3));
    let map = map_of(&[far, near]);
    let truth = Pose2::new(2.0, 0.0, 0.0);
    let sensor = truth.compose(&mount());
    let seen = observe_part(&near, 0.2, 0.8, &sensor, NOISE, None);
    // The filter believes y = 0.2: the far wall's predicted line is closer in NIS.
    let ekf = filter_at(Pose2::new(2.0, 0.2, 0.0));
    let nis = |j: usize| {
        let m = LaserLine::new(seen.line, seen.covariance, map.segments[j].line, mount()).unwrap();
        ekf.innovation(&m).unwrap().nis
    };
    assert!(
        nis(0) < nis(1) && nis(1) < 9.21,
        "both gated, far closer: {} {}",
        nis(0),
        nis(1)
    );
    let mut out = MatchResult::new();
    matcher().match_lines(&[seen], &map, &ekf, &mount(), &mut out);
    assert_eq!(out.matches().len(), 1);
    assert_eq!(
        out.matches()[0].map,
        1,
        "the near wall, which the segment overlaps"
    );
    // Beyond both walls' ends: in the gate of both, overlapping neither.
    let beyond: Wall = (Point2::new(11.0, 2.3), Point2::new(13.0, 2.3));
    let ghost = observe_part(&beyond, 0.0, 1.0, &sensor, NOISE, None);
    matcher().match_lines(&[ghost], &map, &ekf, &mount(), &mut out);
    assert!(out.matches().is_empty());
    assert_eq!(
        out.rejections()[0].reason,
        RejectReason::NoOverlap { map: 0 }
    );
    assert!(out.rejections()[0]
        .reason
        .to_string()
        .starts_with("no overlap"));
}

/// The NIS of pairing `line` with `wall` alone, as the matcher gates it.
fn pair_nis(ekf: &Ekf<f64>, line: &ObservedLine, wall: &MapSegment) -> f64 {
    let noise = matcher().params().line_noise(&line.covariance);
    let m = LaserLine::new(line.line, noise, wall.line, mount()).unwrap();
    ekf.innovation(&m).unwrap().nis
}

/// The joint NIS `D² = yᵀ S⁻¹ y` of matches stacked, `S = H P Hᵀ + R`, computed in one
/// batch at the state matching ran at.
fn batch_joint_nis(out: &MatchResult, p: &Matrix3<f64>) -> f64 {
    let k = out.matches().len();
    let (mut y, mut h, mut r) = (
        nalgebra::DVector::zeros(2 * k),
        nalgebra::DMatrix::zeros(2 * k, 3),
        nalgebra::DMatrix::zeros(2 * k, 2 * k),
    );
    for (i, m) in out.matches().iter().enumerate() {
        let inn = &m.innovation;
        y.rows_mut(2 * i, 2).copy_from(&inn.y);
        h.view_mut((2 * i, 0), (2, 3)).copy_from(&inn.h);
        let ri = inn.s - inn.h * p * inn.h.transpose();
        r.view_mut((2 * i, 2 * i), (2, 2)).copy_from(&ri);
    }
    let pd = nalgebra::DMatrix::from_iterator(3, 3, p.iter().copied());
    let s = &h * pd * h.transpose() + r;
    (y.transpose() * s.try_inverse().unwrap() * &y)[(0, 0)]
}

#[test]
fn lines_are_paired_so_that_one_pose_explains_them_all() {
    // A corridor (walls at y = ±1) with another wall 1.2 m beyond its right wall.
    let left: Wall = (Point2::new(0.0, 1.0), Point2::new(10.0, 1.0));
    let right: Wall = (Point2::new(0.0, -1.0), Point2::new(10.0, -1.0));
    let beyond: Wall = (Point2::new(0.0, -2.2), Point2::new(10.0, -2.2));
    let map = map_of(&[left, right, beyond]);
    let truth = Pose2::new(3.0, 0.0, 0.0);
    let observed = see(&[left, right], &truth);
    // The filter believes the robot 0.65 m to the right, with σ = 0.6 m.
    let p = Matrix3::from_diagonal(&Vector3::new(0.36, 0.36, 2.0_f64.to_radians().powi(2)));
    let ekf = Ekf::new(Pose2::new(3.0, -0.65, 0.0), p).unwrap();
    let nis = |i: usize, j: usize| pair_nis(&ekf, &observed[i], &map.segments[j]);
    // Each line alone fits: the right line even fits the wall beyond better than its own,
    // so the nearest wall of each line would put the robot both up and down at once.
    assert!(nis(1, 2) < nis(1, 1) && nis(1, 1) < 9.21 && nis(0, 0) < 9.21);
    let mut out = MatchResult::new();
    matcher().match_lines(&observed, &map, &ekf, &mount(), &mut out);
    let pairs: Vec<(usize, usize)> = out.matches().iter().map(|m| (m.observed, m.map)).collect();
    let mut sorted = pairs.clone();
    sorted.sort_unstable();
    assert_eq!(sorted, [(0, 0), (1, 1)], "one pose: 0.65 m to the left");
    let threshold = ekf_core::chi_square_quantile(0.99, 4).unwrap();
    let d2 = batch_joint_nis(&out, &p);
    assert!(d2 <= threshold, "jointly compatible: {d2} > {threshold}");

    // A line that no pose shared with the others explains stays unmatched, even where
    // it fits a wall best of all on its own: something 0.35 m to the right of the robot
    // (a row of boxes along the corridor), just where the filter expects the right wall.
    let boxes: Wall = (Point2::new(0.0, -0.35), Point2::new(10.0, -0.35));
    let mut with_boxes = observed.clone();
    with_boxes.push(see(&[boxes], &truth)[0]);
    let box_nis = pair_nis(&ekf, &with_boxes[2], &map.segments[1]);
    assert!(
        box_nis < nis(1, 1),
        "the boxes fit the right wall best: {box_nis}"
    );
    matcher().match_lines(&with_boxes, &map, &ekf, &mount(), &mut out);
    let mut pairs: Vec<(usize, usize)> =
        out.matches().iter().map(|m| (m.observed, m.map)).collect();
    pairs.sort_unstable();
    assert_eq!(pairs, [(0, 0), (1, 1)]);
    assert_eq!(out.rejections().len(), 1);
    assert_eq!(out.rejections()[0].observed, 2);
    assert_eq!(
        out.rejections()[0].reason,
        RejectReason::MapLineTaken { map: 1, by: 1 }
    );

    // A line that fits only a wall nobody took, at a pose the others rule out: 2.5 m to
    // the right fits the wall beyond (predicted 1.55 m) alone, but needs the robot
    // 0.95 m further right where the corridor's walls put it 0.65 m left.
    let far: Wall = (Point2::new(0.0, -2.5), Point2::new(10.0, -2.5));
    let mut with_far = observed.clone();
    with_far.push(see(&[far], &truth)[0]);
    matcher().match_lines(&with_far, &map, &ekf, &mount(), &mut out);
    assert_eq!(out.matches().len(), 2);
    assert_eq!(out.rejections().len(), 1);
    assert_eq!(
        out.rejections()[0].reason,
        RejectReason::Incompatible { map: 2 }
    );
    assert!(out.rejections()[0]
        .reason
        .to_string()
        .starts_with("not jointly compatible"));
}

#[test]
fn a_map_line_is_used_once_by_the_best_fitting_line() {
    let wall: Wall = (Point2::new(4.0, -3.0), Point2::new(4.0, 3.0));
    let map = map_of(&[wall]);
    let truth = Pose2::new(0.0, 0.0, 0.0);
    let sensor = truth.compose(&mount());
    // Two pieces of the same wall; the second 5 cm off (a door frame), so a worse fit.
    let good = observe_part(&wall, 0.0, 0.4, &sensor, NOISE, None);
    let shifted: Wall = (Point2::new(4.05, -3.0), Point2::new(4.05, 3.0));
    let worse = observe_part(&shifted, 0.6, 1.0, &sensor, NOISE, None);
    let mut out = MatchResult::new();
    matcher().match_lines(&[worse, good], &map, &filter_at(truth), &mount(), &mut out);
    assert_eq!(out.matches().len(), 1);
    assert_eq!((out.matches()[0].observed, out.matches()[0].map), (1, 0));
    assert_eq!(out.rejections()[0].observed, 0);
    assert_eq!(
        out.rejections()[0].reason,
        RejectReason::MapLineTaken { map: 0, by: 1 }
    );
    assert!(out.rejections()[0]
        .reason
        .to_string()
        .contains("map line 0 went to observed line 1"));
}

#[test]
fn invalid_lines_are_rejected_not_fatal() {
    let walls = rect_room(-1.0, -1.0, 5.0, 3.0);
    let truth = Pose2::new(1.0, 1.0, 0.0);
    let mut observed = see(&walls, &truth);
    observed[1].covariance = Matrix2::new(1.0, 2.0, 2.0, 1.0);
    observed[2].line.rho = f64::NAN;
    let mut map = map_of(&walls);
    map.segments.push(MapSegment {
        line: Line {
            rho: f64::INFINITY,
            beta: 0.0,
        },
        start: Point2::origin(),
        end: Point2::new(1.0, 0.0),
    });
    let mut out = MatchResult::new();
    matcher().match_lines(&observed, &map, &filter_at(truth), &mount(), &mut out);
    assert_eq!(out.matches().len(), 2);
    assert!(matches!(
        out.rejections()[0].reason,
        RejectReason::InvalidLine(_)
    ));
    assert!(matches!(
        out.rejections()[1].reason,
        RejectReason::InvalidLine(_)
    ));
    // An empty map rejects everything as outside the gate.
    matcher().match_lines(
        &observed[..1],
        &LineMap::default(),
        &filter_at(truth),
        &mount(),
        &mut out,
    );
    assert_eq!(out.rejections()[0].reason, RejectReason::OutsideGate);
    assert!(Matcher::new(MatchParams {
        gate_probability: 1.0,
        ..MatchParams::default()
    })
    .is_err());
    assert!(Matcher::new(MatchParams {
        min_overlap: -1.0,
        ..MatchParams::default()
    })
    .is_err());
}

fn any_f64() -> impl Strategy<Value = f64> {
    prop_oneof![8 => -20.0..20.0, 1 => Just(f64::NAN), 1 => Just(0.0), 1 => Just(1e300)]
}

fn observed_line() -> impl Strategy<Value = ObservedLine> {
    (
        0.0..10.0,
        -PI..PI,
        any_f64(),
        any_f64(),
        any_f64(),
        any_f64(),
        1e-6..1.0_f64,
        -1.0..1.0_f64,
        1e-6..1.0_f64,
    )
        .prop_map(|(r, psi, x0, y0, x1, y1, a, c, b)| ObservedLine {
            line: Line::new(r, psi).unwrap(),
            covariance: Matrix2::new(a, c * (a * b).sqrt(), c * (a * b).sqrt(), b),
            start: Point2::new(x0, y0),
            end: Point2::new(x1, y1),
            num_points: 10,
        })
}

fn segment() -> impl Strategy<Value = MapSegment> {
    (-10.0..10.0, -10.0..10.0, -10.0..10.0, -10.0..10.0)
        .prop_filter_map("zero length", |(x0, y0, x1, y1)| {
            MapSegment::from_points(Point2::new(x0, y0), Point2::new(x1, y1)).ok()
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    #[test]
    fn matching_never_panics_and_never_uses_a_wall_twice(
        observed in proptest::collection::vec(observed_line(), 0..20),
        segments in proptest::collection::vec(segment(), 0..15),
        (x, y, theta) in (-5.0..5.0, -5.0..5.0, -PI..PI),
        (sxy, st) in (1e-4..4.0, 1e-4..1.0),
        params in (0.5..0.999, 0.0..1.0, 0.0..1.0),
    ) {
        let map = LineMap::new(segments);
        let ekf = Ekf::new(Pose2::new(x, y, theta), Matrix3::from_diagonal(&Vector3::new(sxy, sxy, st))).unwrap();
        let matcher = Matcher::new(MatchParams { gate_probability: params.0, min_overlap: params.1, min_overlap_fraction: params.2, ..MatchParams::default() }).unwrap();
        let mut out = MatchResult::new();
        matcher.match_lines(&observed, &map, &ekf, &mount(), &mut out);
        let walls: HashSet<usize> = out.matches().iter().map(|m| m.map).collect();
        prop_assert_eq!(walls.len(), out.matches().len());
        let mut seen: Vec<usize> = out.matches().iter().map(|m| m.observed)
            .chain(out.rejections().iter().map(|r| r.observed)).collect();
        seen.sort_unstable();
        prop_assert_eq!(seen, (0..observed.len()).collect::<Vec<_>>());
        for m in out.matches() {
            prop_assert!(m.map < map.len());
            prop_assert!(matcher.gate().accepts(m.innovation.nis));
        }
        // The matches are jointly compatible, computed in one batch (the search adds the
        // pairs one at a time); a relative margin for the rounding of either way.
        let k = out.matches().len();
        if k > 0 {
            let threshold = ekf_core::chi_square_quantile(params.0, 2 * k as u32).unwrap();
            let d2 = batch_joint_nis(&out, ekf.covariance());
            prop_assert!(d2 <= threshold * (1.0 + 1e-6), "D² {} > {}", d2, threshold);
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(100))]

    /// A result reused from a scan against another map (whose walls share some `β` with
    /// this one's, some not, and may be fewer or more) matches exactly as a fresh one:
    /// nothing of the last scan's walls leaks into this scan's decisions.
    #[test]
    fn a_reused_result_matches_as_a_fresh_one(
        observed in proptest::collection::vec(observed_line(), 0..12),
        segments in proptest::collection::vec(segment(), 1..12),
        before in proptest::collection::vec(segment(), 0..12),
        shared in 0usize..12,
        (x, y, theta) in (-5.0..5.0, -5.0..5.0, -PI..PI),
    ) {
        let ekf = Ekf::new(Pose2::new(x, y, theta), Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, 0.3))).unwrap();
        // The earlier map: its own walls, its first `shared` ones moved off this map's
        // walls along their line (same β, other extent).
        let earlier: Vec<MapSegment> = before.iter().enumerate().map(|(j, s)| match segments.get(j) {
            Some(w) if j < shared => {
                let shift = w.end - w.start;
                MapSegment::from_points(w.start + shift, w.end + shift * 2.0).unwrap()
            }
            _ => *s,
        }).collect();
        let matcher = matcher();
        let mut reused = MatchResult::new();
        matcher.match_lines(&observed, &LineMap::new(earlier), &ekf, &mount(), &mut reused);
        let map = LineMap::new(segments);
        matcher.match_lines(&observed, &map, &ekf, &mount(), &mut reused);
        let mut fresh = MatchResult::new();
        matcher.match_lines(&observed, &map, &ekf, &mount(), &mut fresh);
        prop_assert_eq!(format!("{:?}", reused.matches()), format!("{:?}", fresh.matches()));
        prop_assert_eq!(format!("{:?}", reused.rejections()), format!("{:?}", fresh.rejections()));
    }
}
