//! Loss and relocalization over ray-cast scans: a relocalization's candidate the
//! odometry carries with a heading error larger than the search's tolerance is found
//! again within its own uncertainty and scored where the scan fits; a lost filter is not
//! called found again by two parallel walls.

#[path = "../../lrf-lines/tests/matching_support/mod.rs"]
mod matching_support;

use ekf_core::{Motion, Pose2};
use ekf_fusion::motion::MotionStep;
use ekf_fusion::verification::{restart_covariance, Verification};
use ekf_fusion::{Fuser, FusionConfig, Input, Mode, Scan, Tracking};
use lrf_lines::{
    Hypothesis, LaserScan, LineMap, Localizer, LocalizerConfig, Relocalization, RelocalizeParams,
};
use matching_support::{map_of, ray_cast, Beams, Wall};
use nalgebra::{Matrix3, Point2, Vector3};

/// An L-shaped room: no two places in it look alike.
fn l_room() -> Vec<Wall> {
    let p = Point2::new;
    vec![
        (p(0.0, 0.0), p(8.0, 0.0)),
        (p(8.0, 0.0), p(8.0, 3.0)),
        (p(8.0, 3.0), p(3.0, 3.0)),
        (p(3.0, 3.0), p(3.0, 7.0)),
        (p(3.0, 7.0), p(0.0, 7.0)),
        (p(0.0, 7.0), p(0.0, 0.0)),
    ]
}

/// 361 beams over a full turn, 1° apart.
const BEAMS: Beams = Beams {
    angle_min: -std::f64::consts::PI,
    increment: std::f64::consts::PI / 180.0,
    count: 361,
    range_max: 20.0,
};

/// A localizer in `map` whose last scan was taken at `truth` (its own estimate is
/// elsewhere: only the scan's lines matter here).
fn scanned_at(map: LineMap, truth: &Pose2<f64>) -> Localizer {
    let ranges = ray_cast(&l_room(), truth, &BEAMS, 0.0, None);
    let scan = LaserScan {
        angle_min: BEAMS.angle_min,
        angle_increment: BEAMS.increment,
        range_min: 0.05,
        range_max: BEAMS.range_max,
        ranges: &ranges,
    };
    let params = RelocalizeParams::default();
    let mut localizer = Localizer::new(
        LocalizerConfig::default(),
        Pose2::new(5.0, 1.5, 2.0),
        restart_covariance(&params),
        map,
    )
    .unwrap();
    localizer.update_scan(&scan).unwrap();
    assert!(
        localizer.last_lines().len() >= 4,
        "the room's walls are seen"
    );
    localizer
}

#[test]
fn a_candidate_carried_with_a_heading_error_is_found_within_its_uncertainty() {
    let params = RelocalizeParams::default();
    let start = Pose2::new(1.5, 1.5, 0.0);
    // The robot drove 1 m and turned 0.5 rad; the odometry says it turned 0.35 rad
    // (8.6° short), within the default noise's 3σ but far beyond the search's 3°.
    let truth = start.compose(&Pose2::new(
        1.0 * (0.25f64).cos(),
        1.0 * (0.25f64).sin(),
        0.5,
    ));
    let found = Relocalization {
        best: Hypothesis {
            pose: start,
            inliers: 4,
            score: 10.0,
        },
        runner_up: 0.0,
        candidates: vec![Hypothesis {
            pose: start,
            inliers: 4,
            score: 10.0,
        }],
        observed_length: 10.0,
        hypotheses: 1,
    };
    let mut v = Verification::start(&found, &params).unwrap();
    v.predict(
        MotionStep::Odometry(Motion {
            ds: 1.0,
            dtheta: 0.35,
        }),
        &LocalizerConfig::default(),
    )
    .unwrap();
    let localizer = scanned_at(map_of(&l_room()), &truth);
    let fits = v.fits(&localizer, &params);
    let fit = fits.fits[0];
    assert!(
        (fit.pose.x - truth.x).abs() < 0.02
            && (fit.pose.y - truth.y).abs() < 0.02
            && ekf_core::angle_diff(fit.pose.theta, truth.theta).abs() < 1f64.to_radians(),
        "{fit:?} against {truth:?}"
    );
    assert!(
        fit.score > 0.9 * fits.observed_length,
        "{fit:?} of {fits:?}"
    );
    // Where the odometry carried it (along the mid-angle, as the motion model moves it),
    // the scan's lines do not lie on the walls.
    let odometry = Pose2::new((0.175f64).cos(), (0.175f64).sin(), 0.35);
    let carried = localizer
        .fit_poses(&[start.compose(&odometry)], &params)
        .fits[0];
    assert!(carried.score < 0.5 * fit.score, "{carried:?}");
}

#[test]
fn a_candidate_is_not_moved_beyond_its_uncertainty() {
    // The candidate is 1.1 m and 20° from where the robot is: the right pose lies outside
    // its window (0.46 m, 7.7°), so it is scored where it was carried, and scores little
    // there.
    let params = RelocalizeParams::default();
    let truth = Pose2::new(2.5, 1.5, 0.0);
    let wrong = Pose2::new(1.5, 2.0, 0.35);
    let hypothesis = Hypothesis {
        pose: wrong,
        inliers: 3,
        score: 5.0,
    };
    let found = Relocalization {
        best: hypothesis,
        runner_up: 0.0,
        candidates: vec![hypothesis],
        observed_length: 10.0,
        hypotheses: 1,
    };
    let v = Verification::start(&found, &params).unwrap();
    let localizer = scanned_at(map_of(&l_room()), &truth);
    let fit = v.fits(&localizer, &params).fits[0];
    assert_eq!(fit.pose, wrong);
    assert!(fit.score < 0.5 * localizer.fit_poses(&[truth], &params).fits[0].score);
}

/// A corridor along x, 2 m wide, closed at x = 6 by an end wall.
fn corridor() -> Vec<Wall> {
    let p = Point2::new;
    vec![
        (p(-20.0, 1.0), p(6.0, 1.0)),
        (p(-20.0, -1.0), p(6.0, -1.0)),
        (p(6.0, -1.0), p(6.0, 1.0)),
    ]
}

/// A scan from `pose` among `walls` with 361 beams over a full turn, seeing up to
/// `range_max`.
fn scan_among(walls: &[Wall], pose: &Pose2<f64>, range_max: f64) -> Input {
    let beams = Beams { range_max, ..BEAMS };
    Input::Scan(Scan {
        angle_min: beams.angle_min,
        angle_increment: beams.increment,
        range_min: 0.05,
        range_max,
        ranges: ray_cast(walls, pose, &beams, 0.0, None),
    })
}

#[test]
fn a_lost_filter_is_found_again_by_a_corner_not_by_two_parallel_walls() {
    let config = FusionConfig {
        mode: Mode::Laser,
        tracking: Tracking::FromInitialPose,
        ..FusionConfig::default()
    };
    let at = Pose2::new(0.0, 0.0, 0.0);
    let p0 = Matrix3::from_diagonal(&Vector3::new(0.01, 0.01, 0.001));
    let mut fuser = Fuser::new(&config, at, p0, 0, Some(map_of(&corridor()))).unwrap();
    let mut t = 0;
    let mut fuse = |fuser: &mut Fuser, input: &Input| {
        t += 100_000_000;
        fuser.fuse(t, input, &mut ()).unwrap();
    };
    // Three scans of a room the map does not have (a square 7 m across, turned 30°):
    // lines, none fused: lost.
    let p = Point2::new;
    let elsewhere: Vec<Wall> = [(-3.5, -3.5), (3.5, -3.5), (3.5, 3.5), (-3.5, 3.5)]
        .iter()
        .zip([(3.5, -3.5), (3.5, 3.5), (-3.5, 3.5), (-3.5, -3.5)])
        .map(|(&(x0, y0), (x1, y1))| {
            let turn = Pose2::new(0.3, -0.2, 30f64.to_radians());
            (
                turn.transform_point(&p(x0, y0)),
                turn.transform_point(&p(x1, y1)),
            )
        })
        .collect();
    for _ in 0..3 {
        fuse(&mut fuser, &scan_among(&elsewhere, &at, 20.0));
    }
    assert!(
        fuser.lost_for() > 0,
        "lines and none fused three times: lost"
    );
    // The corridor's two walls, the end wall out of reach: they fuse, but a place along
    // the corridor is not fixed by them, and the search finds no pose in parallel lines.
    for _ in 0..3 {
        fuse(&mut fuser, &scan_among(&corridor(), &at, 4.0));
        assert_eq!(
            fuser
                .localizer()
                .last_fusions()
                .iter()
                .filter(|f| f.accepted)
                .count(),
            2
        );
        assert!(
            fuser.lost_for() > 0,
            "two parallel walls do not end the loss"
        );
    }
    // The end wall comes into reach: a corner.
    fuse(&mut fuser, &scan_among(&corridor(), &at, 10.0));
    assert_eq!(fuser.lost_for(), 0, "{:?}", fuser.counts().tracking);
    let pose = fuser.localizer().pose();
    assert!(pose.x.abs() < 0.01 && pose.y.abs() < 0.01, "{pose:?}");
}

/// Fuses `input` at `t_ns`; a scan's outcome.
fn scan_outcome(fuser: &mut Fuser, t_ns: u64, input: &Input) -> ekf_fusion::ScanFused {
    match fuser.fuse(t_ns, input, &mut ()).unwrap() {
        ekf_fusion::Fused::Scan(s) => s,
        other => panic!("not a scan's outcome: {other:?}"),
    }
}

/// A laser-only fuser with `tracking`, started at (1.5, 1.5, 0) (σ 0.1 m, 0.03 rad) in
/// the L room's map; the room's walls and that pose.
fn laser_fuser_in_the_l_room(tracking: Tracking) -> (Fuser, Vec<Wall>, Pose2<f64>) {
    let config = FusionConfig {
        mode: Mode::Laser,
        tracking,
        ..FusionConfig::default()
    };
    let room = l_room();
    let a = Pose2::new(1.5, 1.5, 0.0);
    let p0 = Matrix3::from_diagonal(&Vector3::new(0.01, 0.01, 0.001));
    let fuser = Fuser::new(&config, a, p0, 0, Some(map_of(&room))).unwrap();
    (fuser, room, a)
}

#[test]
fn after_a_motion_gap_one_scans_answer_stays_unconfirmed_until_a_tracked_scan_fixes_it() {
    const MS: u64 = 1_000_000;
    let (mut fuser, room, a) = laser_fuser_in_the_l_room(Tracking::FromInitialPose);
    // The robot's own odometry stands still throughout: it is carried, not driven.
    let odometry = Input::OdometryPose(Pose2::new(0.0, 0.0, 0.0));
    let mut t = 0;
    for _ in 0..5 {
        t += 50 * MS;
        fuser.fuse(t, &odometry, &mut ()).unwrap();
        t += 50 * MS;
        let s = scan_outcome(&mut fuser, t, &scan_among(&room, &a, 20.0));
        assert!(s.lost.is_none() && !s.lost_after, "tracking at A: {s:?}");
        assert!(!s.motion_gap, "{s:?}");
    }
    // Carried 1.5 m and turned while the odometry is silent for 2 s: a motion gap, and
    // the search alone places the robot. One scan's word: still lost.
    let b = Pose2::new(3.0, 1.8, 0.6);
    t += 2000 * MS;
    let s = scan_outcome(&mut fuser, t, &scan_among(&room, &b, 20.0));
    assert!(
        s.lost.is_some_and(|l| l.motion_gap) && s.motion_gap,
        "{s:?}"
    );
    assert!(s.relocalized.is_some() && s.lost_after, "{s:?}");
    let pose = fuser.localizer().pose();
    assert!((pose.x - b.x).hypot(pose.y - b.y) < 0.05, "{pose:?}");
    assert_eq!(fuser.counts().tracking.relocalizations, 1);
    // Another silent scan from the same place: the search agrees with the estimate, but
    // that estimate was one scan's answer too. Still lost, and no new loss.
    t += 2000 * MS;
    let s = scan_outcome(&mut fuser, t, &scan_among(&room, &b, 20.0));
    assert!(
        s.lost.is_none() && s.regained.is_none() && s.lost_after,
        "{s:?}"
    );
    assert_eq!(fuser.counts().tracking.losses, 1);
    assert_eq!(fuser.lost_for(), 2);
    // The odometry speaks again and the next scan, tracked from there, fuses the room's
    // corner: confirmed, and the loss is reported as regained.
    t += 50 * MS;
    fuser.fuse(t, &odometry, &mut ()).unwrap();
    t += 50 * MS;
    let s = scan_outcome(&mut fuser, t, &scan_among(&room, &b, 20.0));
    assert!(s.regained.is_some() && !s.lost_after, "{s:?}");
    assert_eq!(fuser.lost_for(), 0);
    assert_eq!(fuser.counts().tracking.scans_lost, 2);
}

#[test]
fn a_motion_gap_is_reported_with_loss_detection_off() {
    const MS: u64 = 1_000_000;
    let (mut fuser, room, a) = laser_fuser_in_the_l_room(Tracking::Off);
    let odometry = Input::OdometryPose(Pose2::new(0.0, 0.0, 0.0));
    let mut t = 0;
    let mut gaps = Vec::new();
    // Odometry every 100 ms with a scan after each, then 2 s of silence before a scan.
    for silent_ms in [0, 0, 0, 0, 2000, 0] {
        t += 50 * MS;
        if silent_ms == 0 {
            fuser.fuse(t, &odometry, &mut ()).unwrap();
        }
        t += 50 * MS + silent_ms * MS;
        let s = scan_outcome(&mut fuser, t, &scan_among(&room, &a, 20.0));
        assert!(s.lost.is_none() && s.relocalized.is_none(), "{s:?}");
        gaps.push(s.motion_gap);
    }
    assert_eq!(gaps, [false, false, false, false, true, false]);
    assert_eq!(fuser.counts().tracking.losses, 0);
}
