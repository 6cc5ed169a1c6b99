//! The Localizer on a simulated run: ray-cast scans, biased odometry, a noisy compass.

mod localizer_sim;
mod matching_support;

use ekf_core::{angle_diff, wrap_angle, DiffDrive, Motion, Pose2, WheelSpeeds};
use localizer_sim::{commands, measured, mount, ranges, scan, start, walls};
use lrf_lines::{
    CompassConfig, CompassUpdate, ExtractionError, ExtractionParams, LineMap, Localizer,
    LocalizerConfig, LocalizerError,
};
use matching_support::{map_of, Rng};
use nalgebra::{Matrix3, Vector3};

fn config() -> LocalizerConfig {
    LocalizerConfig {
        laser_mount: mount(),
        ..LocalizerConfig::default()
    }
}

fn initial_covariance() -> Matrix3<f64> {
    Matrix3::from_diagonal(&Vector3::new(1e-4, 1e-4, 1.0_f64.to_radians().powi(2)))
}

/// Fails unless `p` is symmetric and positive definite.
fn assert_spd(p: &Matrix3<f64>, step: usize) {
    assert!(
        (p - p.transpose()).abs().max() <= 1e-12 * p.abs().max(),
        "step {step}: asymmetric {p}"
    );
    assert!(
        p.cholesky().is_some(),
        "step {step}: not positive definite {p}"
    );
}

/// Statistics of one simulated lap.
struct Lap {
    max_position_error: f64,
    max_heading_error: f64,
    rms_position_error: f64,
    scans_with_fusion: usize,
    scans: usize,
    odometry_only_final_error: f64,
    /// Steps whose NEES `eᵀ P⁻¹ e` is within the 99 % chi-square bound (3 dof, 11.34).
    consistent_steps: usize,
}

impl std::fmt::Display for Lap {
    /// The errors, the fused scans and the consistent steps.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "max {:.4} m, rms {:.4} m, max heading {:.3}°, {}/{} scans fused, {} consistent",
            self.max_position_error,
            self.rms_position_error,
            self.max_heading_error.to_degrees(),
            self.scans_with_fusion,
            self.scans,
            self.consistent_steps
        )
    }
}

/// Drives one lap; scans every step, compass every other step.
fn lap(localizer: &mut Localizer, seed: u64) -> Lap {
    let walls = walls();
    let robot = DiffDrive::paper();
    let mut rng = Rng::new(seed);
    let mut truth = start();
    let mut dead_reckoning = start();
    let (mut max_pos, mut max_head, mut sum_sq, mut fused_scans) = (0.0_f64, 0.0_f64, 0.0, 0);
    let mut consistent = 0;
    let commands = commands();
    for (k, cmd) in commands.iter().enumerate() {
        truth = robot.motion(cmd).apply(&truth);
        let odo = measured(cmd, &mut rng);
        dead_reckoning = robot.motion(&odo).apply(&dead_reckoning);
        localizer.predict_wheels(&odo).unwrap();
        if k % 2 == 0 {
            let heading = truth.theta + 2.0_f64.to_radians() * rng.normal_floored();
            localizer.update_compass(heading).unwrap();
        }
        let r = ranges(&truth, &walls, &mut rng);
        let report = localizer.update_scan(&scan(&r)).unwrap();
        if report.fused > 0 {
            fused_scans += 1;
        }
        assert_eq!(report.matched + report.rejected, report.extracted);
        assert_eq!(report.fused + report.refused, report.matched);
        let pose = localizer.pose();
        let e = ((pose.x - truth.x).powi(2) + (pose.y - truth.y).powi(2)).sqrt();
        max_pos = max_pos.max(e);
        max_head = max_head.max(angle_diff(pose.theta, truth.theta).abs());
        sum_sq += e * e;
        assert_spd(localizer.covariance(), k);
        let err = Vector3::new(
            pose.x - truth.x,
            pose.y - truth.y,
            angle_diff(pose.theta, truth.theta),
        );
        let nees = err.dot(&(localizer.covariance().try_inverse().unwrap() * err));
        if nees <= 11.34 {
            consistent += 1;
        }
    }
    Lap {
        max_position_error: max_pos,
        max_heading_error: max_head,
        rms_position_error: (sum_sq / commands.len() as f64).sqrt(),
        scans_with_fusion: fused_scans,
        scans: commands.len(),
        odometry_only_final_error: ((dead_reckoning.x - truth.x).powi(2)
            + (dead_reckoning.y - truth.y).powi(2))
        .sqrt(),
        consistent_steps: consistent,
    }
}

#[test]
fn a_lap_with_a_known_map_stays_accurate_and_consistent() {
    // The map here is the simulation's own walls, exact: no map noise.
    let mut exact = config();
    exact.matching.map_sigma_r = 0.0;
    exact.matching.map_sigma_psi = 0.0;
    let mut localizer =
        Localizer::new(exact, start(), initial_covariance(), map_of(&walls())).unwrap();
    let lap = lap(&mut localizer, 1);
    let summary = format!(
        "{lap}, odometry alone {:.3} m",
        lap.odometry_only_final_error
    );
    assert!(
        lap.odometry_only_final_error > 0.3,
        "the run must be hard: {summary}"
    );
    // Measured at commit time: max 1.6 mm, rms 0.5 mm, 0.033°.
    assert!(lap.max_position_error < 0.01, "{summary}");
    assert!(lap.rms_position_error < 0.003, "{summary}");
    assert!(lap.max_heading_error < 0.2_f64.to_radians(), "{summary}");
    // The covariance is honest: the error is inside its 99 % ellipsoid almost always.
    assert!(lap.consistent_steps * 100 >= lap.scans * 95, "{summary}");
    assert_eq!(lap.scans_with_fusion, lap.scans, "{summary}");
    // The diagnostics of the last scan are there for visualisation.
    assert!(!localizer.last_lines().is_empty());
    assert_eq!(
        localizer.last_matches().matches().len(),
        localizer.last_fusions().len()
    );
    assert!(localizer
        .last_fusions()
        .iter()
        .all(|f| f.accepted && f.nis <= 9.2104));
}

#[test]
fn a_lap_with_the_first_scan_map_stays_accurate() {
    // The robot is set down on its start mark (to 1 mm and 0.1°), and the first-scan map
    // is placed there: a looser prior would say the map may be rotated by as much, and
    // the filter would rightly hedge against an error that this run does not have.
    let on_the_mark =
        Matrix3::from_diagonal(&Vector3::new(1e-6, 1e-6, 0.1_f64.to_radians().powi(2)));
    let mut localizer = Localizer::with_first_scan_map(config(), start(), on_the_mark).unwrap();
    let mut rng = Rng::new(99);
    let r = ranges(&start(), &walls(), &mut rng);
    let report = localizer.update_scan(&scan(&r)).unwrap();
    assert!(report.map_built && report.fused == 0);
    // From (0.5, 0.5) facing +x the laser sees the right, bottom and top walls.
    assert!(localizer.map().len() >= 3, "{:#?}", localizer.map());
    assert_eq!(localizer.map().len(), report.extracted);
    let lap = lap(&mut localizer, 2);
    let summary = format!("{lap}, map {:#?}", localizer.map());
    // The left wall is not in this map: facing it, the heading rests on the compass
    // (σ = 2°) and the biased odometry alone, hence the looser heading bound. The map is
    // one noisy scan, and each wall carries its fit error as a considered error, so the
    // filter stays consistent (measured: max 8.3 cm, rms 2.7 cm, 480 of 480 steps inside
    // the 99 % bound; with the walls' error as fresh noise on every scan and no map noise,
    // only 54 of 480 were).
    assert!(lap.consistent_steps * 100 >= lap.scans * 95, "{summary}");
    assert!(lap.max_position_error < 0.10, "{summary}");
    assert!(lap.rms_position_error < 0.03, "{summary}");
    assert!(lap.max_heading_error < 2.5_f64.to_radians(), "{summary}");
    assert!(lap.scans_with_fusion * 10 >= lap.scans * 9, "{summary}");
}

#[test]
fn a_compass_outlier_is_gated_out() {
    let mut localizer =
        Localizer::new(config(), start(), initial_covariance(), map_of(&walls())).unwrap();
    let (pose, p) = (localizer.pose(), *localizer.covariance());
    let outcome = localizer
        .update_compass(pose.theta + 90.0_f64.to_radians())
        .unwrap();
    assert!(!outcome.outcome.accepted && outcome.outcome.nis > 10.83);
    assert_eq!((outcome.rejected_in_a_row, outcome.recovered), (1, false));
    assert_eq!((localizer.pose(), *localizer.covariance()), (pose, p));
    // A consistent heading is fused and shrinks the heading variance.
    let outcome = localizer.update_compass(pose.theta + 0.01).unwrap();
    assert!(outcome.outcome.accepted && !outcome.recovered);
    assert!(localizer.covariance()[(2, 2)] < p[(2, 2)]);
    assert!(matches!(
        localizer.update_compass(f64::NAN),
        Err(LocalizerError::Filter(_))
    ));
}

#[test]
fn bad_config_and_scans_are_named_errors() {
    let build =
        |c: LocalizerConfig| Localizer::new(c, start(), initial_covariance(), LineMap::default());
    // The error of the default config changed by `edit`.
    let refused = |edit: fn(&mut LocalizerConfig)| {
        let mut c = config();
        edit(&mut c);
        build(c).unwrap_err()
    };
    // The same, which must be a config error of `group`.
    let refused_in = |group: &str, edit: fn(&mut LocalizerConfig)| {
        let e = refused(edit);
        assert!(
            matches!(e, LocalizerError::Config { group: g, .. } if g == group),
            "{e}"
        );
        e
    };
    // A value out of its range is named by its key, with what was found.
    let setting = |edit: fn(&mut LocalizerConfig)| match refused(edit) {
        LocalizerError::Setting(s) => s.to_string(),
        e => panic!("not a setting error: {e}"),
    };
    type Edit = fn(&mut LocalizerConfig);
    let cases: [(Edit, &str); 5] = [
        (
            |c| c.robot.track = 0.0,
            "robot.track: expected a finite number > 0, found 0",
        ),
        (
            |c| c.robot.wheel_radius = 50.0,
            "robot.wheel_radius: expected metres in (0, 2], found 50 (millimetres?)",
        ),
        (
            |c| c.laser_mount.theta = 90.0,
            "laser_mount.theta: expected radians within ±2π (6.283), found 90 (degrees?)",
        ),
        (
            |c| c.compass.variance = 0.0,
            "compass.variance: expected a finite number > 0, found 0",
        ),
        (
            |c| c.matching.gate_probability = 2.0,
            "matching.gate_probability: expected a probability in (0, 1), found 2",
        ),
    ];
    for (edit, message) in cases {
        assert_eq!(setting(edit), message);
    }
    // A group's own rules are named by the group.
    refused_in("compass", |c| c.compass.recover_after = 1);
    let e = refused_in("wheel_noise", |c| c.wheel_noise.delta = -1.0);
    assert!(e.to_string().contains("[wheel_noise]"), "{e}");
    refused_in("odometry_noise", |c| c.odometry_noise.a1 = -1.0);
    assert!(matches!(
        refused(|c| c.extraction = ExtractionParams {
            min_points: 1,
            ..ExtractionParams::default()
        }),
        LocalizerError::Extraction(ExtractionError::InvalidParameter {
            name: "min_points",
            ..
        })
    ));
    let nan_pose = Localizer::new(
        config(),
        Pose2::new(f64::NAN, 0.0, 0.0),
        initial_covariance(),
        LineMap::default(),
    );
    assert!(matches!(nan_pose, Err(LocalizerError::Filter(_))));
    // A scan with a broken header is refused and changes nothing.
    let mut localizer = build(config()).unwrap();
    let before = (localizer.pose(), *localizer.covariance());
    let ranges = [1.0_f32; 10];
    let mut bad = scan(&ranges);
    bad.angle_increment = 0.0;
    assert!(matches!(
        localizer.update_scan(&bad),
        Err(LocalizerError::Extraction(_))
    ));
    assert_eq!((localizer.pose(), *localizer.covariance()), before);
    assert!(localizer.last_lines().is_empty() && localizer.last_matches().matches().is_empty());
}

/// A localizer whose heading is `off` degrees off while it believes itself good to 0.5°,
/// with the given compass, and no map (so only the compass can correct it).
fn drifted(compass: CompassConfig, off: f64) -> (Localizer, f64) {
    let mut config = config();
    config.compass = compass;
    // Odometry trusted with 10 % of each turn, so the filter stays confident while it
    // turns (these tests are about what the compass does to a confident filter).
    config.odometry_noise.a3 = 0.1;
    let p = Matrix3::from_diagonal(&Vector3::new(1e-4, 1e-4, 0.5_f64.to_radians().powi(2)));
    let localizer = Localizer::new(config, start(), p, LineMap::default()).unwrap();
    (localizer, start().theta - off.to_radians())
}

fn paper_compass(recover_after: u32) -> CompassConfig {
    CompassConfig {
        recover_after,
        ..CompassConfig::paper()
    }
}

/// Turns 0.02 rad by odometry and reads the compass at the true heading, `n` times.
fn turn_and_read(localizer: &mut Localizer, truth: &mut f64, n: usize) -> Vec<CompassUpdate> {
    let turn = Motion::new(0.02, 0.02).unwrap();
    (0..n)
        .map(|_| {
            localizer.predict_odometry(&turn).unwrap();
            *truth += 0.02;
            localizer.update_compass(*truth).unwrap()
        })
        .collect()
}

#[test]
fn consistent_rejected_headings_end_a_gate_lock_out() {
    let (mut localizer, mut truth) = drifted(paper_compass(3), 8.0);
    let updates = turn_and_read(&mut localizer, &mut truth, 3);
    let in_a_row: Vec<_> = updates.iter().map(|u| u.rejected_in_a_row).collect();
    assert_eq!(in_a_row, [1, 2, 3]);
    assert!(updates[..2]
        .iter()
        .all(|u| !u.outcome.accepted && !u.recovered));
    assert!(updates[2].outcome.accepted && updates[2].recovered);
    // The NIS reported is the heading's at the predicted state, past the gate.
    assert!(updates[2].outcome.nis > 10.83, "{:?}", updates[2]);
    assert!(angle_diff(localizer.pose().theta, truth).abs() < 0.2_f64.to_radians());
    let next = turn_and_read(&mut localizer, &mut truth, 1)[0];
    assert!(next.outcome.accepted && !next.recovered && next.rejected_in_a_row == 0);

    // With recovery off the lock-out lasts (until odometry's noise has grown the
    // covariance to the error).
    let (mut localizer, mut truth) = drifted(paper_compass(0), 8.0);
    let updates = turn_and_read(&mut localizer, &mut truth, 5);
    assert!(updates.iter().all(|u| !u.outcome.accepted && !u.recovered));
}

#[test]
fn a_recovery_trusts_a_coarse_compass_as_much_as_the_lock_out_shows() {
    // A 2° compass against a filter that believes 0.5° and is 8° off: an ordinary update
    // would move the heading by P/(P + σ²) ≈ 6 % of the error. The recovery first adds the
    // error the readings show the filter missed, and takes most of it.
    let (mut localizer, mut truth) = drifted(CompassConfig::default(), 8.0);
    let updates = turn_and_read(&mut localizer, &mut truth, 3);
    assert!(updates[2].recovered, "{updates:?}");
    let error = angle_diff(localizer.pose().theta, truth).abs();
    assert!(error < 1.5_f64.to_radians(), "{}°", error.to_degrees());
    // The heading's NEES is back to what a consistent filter shows.
    assert!(error * error / localizer.covariance()[(2, 2)] < 3.0);
}

#[test]
fn a_bad_reading_within_a_lock_out_changes_nothing() {
    let (mut localizer, mut truth) = drifted(paper_compass(2), 8.0);
    let first = turn_and_read(&mut localizer, &mut truth, 1)[0];
    assert_eq!(
        (first.outcome.accepted, first.rejected_in_a_row),
        (false, 1)
    );
    let before = (localizer.pose(), *localizer.covariance());
    assert!(localizer.update_compass(f64::NAN).is_err());
    assert_eq!((localizer.pose(), *localizer.covariance()), before);
    // The run goes on from the first reading: with recover_after = 2 the next ends it.
    let second = turn_and_read(&mut localizer, &mut truth, 1)[0];
    assert!(
        second.recovered && second.rejected_in_a_row == 2,
        "{second:?}"
    );
}

#[test]
fn a_lock_out_across_plus_minus_pi_ends_with_wheel_predictions() {
    // Heading near π, turning left through it on the wheels; the compass reads the truth
    // 6° ahead of the estimate, across the wrap.
    let mut config = config();
    config.compass = CompassConfig::paper();
    let p = Matrix3::from_diagonal(&Vector3::new(1e-4, 1e-4, 0.3_f64.to_radians().powi(2)));
    let pose = Pose2::new(0.0, 0.0, 179.0_f64.to_radians());
    let mut localizer = Localizer::new(config, pose, p, LineMap::default()).unwrap();
    let mut truth = 185.0_f64.to_radians();
    let speeds = WheelSpeeds::new(2.0, 2.2, 0.1).unwrap();
    let mut updates = Vec::new();
    for _ in 0..3 {
        let before = localizer.pose().theta;
        localizer.predict_wheels(&speeds).unwrap();
        truth += angle_diff(localizer.pose().theta, before);
        updates.push(localizer.update_compass(wrap_angle(truth)).unwrap());
    }
    assert!(updates[2].recovered, "{updates:?}");
    let error = angle_diff(localizer.pose().theta, truth);
    assert!(
        error.abs() < 0.2_f64.to_radians(),
        "{}°",
        error.to_degrees()
    );
}

#[test]
fn a_scan_that_fuses_no_line_does_not_break_the_run() {
    // No map to match against: the scans' lines are extracted, none is fused, and the
    // run of rejected headings goes on to its recovery.
    let (mut localizer, mut truth) = drifted(paper_compass(3), 8.0);
    let mut rng = Rng::new(4);
    let mut in_a_row = Vec::new();
    for _ in 0..3 {
        let update = turn_and_read(&mut localizer, &mut truth, 1)[0];
        in_a_row.push(update.rejected_in_a_row);
        let report = localizer
            .update_scan(&scan(&ranges(&start(), &walls(), &mut rng)))
            .unwrap();
        assert!(report.extracted > 0 && report.fused == 0, "{report:?}");
    }
    assert_eq!(in_a_row, [1, 2, 3]);
}

#[test]
fn a_compass_the_laser_contradicts_stays_rejected() {
    // A disturbance holds the compass 20° off while the laser sees the room's walls at
    // the true pose: each fused line says the filter is right, so no run of rejections
    // builds up, and the steady, self-consistent readings are never fused.
    let mut config = config();
    config.compass = CompassConfig::paper();
    let truth = start();
    let mut localizer =
        Localizer::new(config, truth, initial_covariance(), map_of(&walls())).unwrap();
    let mut rng = Rng::new(3);
    for _ in 0..10 {
        let update = localizer
            .update_compass(truth.theta + 20.0_f64.to_radians())
            .unwrap();
        assert!(
            !update.outcome.accepted && update.rejected_in_a_row == 1,
            "{update:?}"
        );
        let report = localizer
            .update_scan(&scan(&ranges(&truth, &walls(), &mut rng)))
            .unwrap();
        assert!(report.fused > 0);
    }
    assert!(angle_diff(localizer.pose().theta, truth.theta).abs() < 0.5_f64.to_radians());
}

#[test]
fn outliers_in_a_row_do_not_end_a_lock_out() {
    // Twenty readings in a row, each 30°–180° off the truth in a random direction (the
    // simulator's disturbed field): none agrees with the one before, none is fused.
    let (mut localizer, truth) = drifted(paper_compass(3), 8.0);
    let mut rng = Rng::new(5);
    for _ in 0..20 {
        localizer
            .predict_odometry(&Motion::new(0.02, 0.0).unwrap())
            .unwrap();
        let size = (30.0 + 150.0 * rng.uniform()).to_radians();
        let sign = if rng.uniform() < 0.5 { -1.0 } else { 1.0 };
        let update = localizer.update_compass(truth + sign * size).unwrap();
        assert!(!update.outcome.accepted, "{update:?}");
        assert_eq!(update.rejected_in_a_row, 1);
    }
}

#[test]
fn recovery_after_a_single_rejection_is_refused() {
    let mut config = config();
    config.compass.recover_after = 1;
    let error =
        Localizer::new(config, start(), initial_covariance(), LineMap::default()).unwrap_err();
    assert!(matches!(
        error,
        LocalizerError::Config {
            group: "compass",
            ..
        }
    ));
    assert!(error.to_string().contains("recover_after"), "{error}");
}

#[test]
fn config_files_may_omit_groups_and_fields() {
    let c: LocalizerConfig = serde_json::from_str(r#"{"compass": {"variance": 0.01}}"#).unwrap();
    assert_eq!(c.compass.variance, 0.01);
    assert_eq!(c.compass.gate_probability, 0.999);
    assert_eq!(c.robot, DiffDrive::paper());
    assert_eq!(c.matching, Default::default());
    let d = LocalizerConfig::default();
    assert!((d.compass.variance - 2.0_f64.to_radians().powi(2)).abs() < 1e-15);
    assert!((CompassConfig::paper().variance - 3.046e-6).abs() < 1e-9);
    let text = serde_json::to_string(&d).unwrap();
    assert_eq!(serde_json::from_str::<LocalizerConfig>(&text).unwrap(), d);
}

#[test]
fn odometry_prediction_moves_the_pose_and_grows_the_covariance() {
    let mut localizer =
        Localizer::new(config(), start(), initial_covariance(), map_of(&walls())).unwrap();
    let p0 = *localizer.covariance();
    localizer
        .predict_odometry(&Motion::new(0.5, 0.1).unwrap())
        .unwrap();
    // Along the mid-angle heading 0.05 rad.
    let pose = localizer.pose();
    assert!((pose.x - (0.5 + 0.5 * 0.05_f64.cos())).abs() < 1e-12);
    assert!((pose.y - (0.5 + 0.5 * 0.05_f64.sin())).abs() < 1e-12);
    assert!((pose.theta - 0.1).abs() < 1e-12);
    assert!(localizer.covariance()[(0, 0)] > p0[(0, 0)]);
    assert_eq!(localizer.sensor_pose(), pose.compose(&mount()));
    let nan = Motion {
        ds: f64::NAN,
        dtheta: 0.0,
    };
    assert!(matches!(
        localizer.predict_odometry(&nan),
        Err(LocalizerError::Filter(_))
    ));
    assert_eq!(localizer.pose(), pose);
}

#[test]
fn a_robot_standing_still_learns_nothing_from_the_map_its_first_scan_made() {
    // The first scan places the walls at the pose the robot believes it has, so later
    // scans from the same spot can only confirm where the robot is relative to them: the
    // gain is K = P0 (Hᵀ + Gᵀ H_mᵀ) S⁻¹ = 0 exactly (G = −H_m⁻¹ H). Treating the walls'
    // error as fresh noise on every scan would shrink P for nothing.
    let mut rng = Rng::new(5);
    let p0 = initial_covariance();
    let mut localizer = Localizer::with_first_scan_map(config(), start(), p0).unwrap();
    let first = localizer
        .update_scan(&scan(&ranges(&start(), &walls(), &mut rng)))
        .unwrap();
    assert!(first.map_built);
    let mut fused = 0;
    for _ in 0..20 {
        let report = localizer
            .update_scan(&scan(&ranges(&start(), &walls(), &mut rng)))
            .unwrap();
        fused += report.fused;
    }
    assert!(fused >= 40, "{fused} lines fused");
    let (pose, p) = (localizer.pose(), *localizer.covariance());
    let moved = (pose.to_vector() - start().to_vector()).amax();
    assert!(moved < 1e-12, "moved by {moved}");
    assert!((p - p0).amax() < 1e-12 * p0.amax(), "{p} vs {p0}");

    // The same walls given as a map are taken as exact up to the map noise, fresh on
    // every scan: P shrinks.
    let map = localizer.map().clone();
    let mut given = Localizer::new(config(), start(), p0, map).unwrap();
    for _ in 0..20 {
        given
            .update_scan(&scan(&ranges(&start(), &walls(), &mut rng)))
            .unwrap();
    }
    assert!(
        given.covariance()[(0, 0)] < 0.5 * p0[(0, 0)],
        "{}",
        given.covariance()
    );
}

#[test]
fn a_compass_turns_a_first_scan_map_placed_with_a_heading_error_into_its_frame() {
    // The robot believes it faces 2° left of where it does, and places the first-scan map
    // there, turned by 2°. The compass measures the true heading: the filter estimates the
    // placement's error with the pose and turns the map back, rigidly.
    let error = 2.0_f64.to_radians();
    let truth = start();
    let believed = Pose2::new(truth.x, truth.y, truth.theta + error);
    let p0 = Matrix3::from_diagonal(&Vector3::new(1e-6, 1e-6, error * error));
    let mut rng = Rng::new(11);
    let mut localizer = Localizer::with_first_scan_map(config(), believed, p0).unwrap();
    localizer
        .update_scan(&scan(&ranges(&truth, &walls(), &mut rng)))
        .unwrap();
    let placed = localizer.map().clone();
    for _ in 0..50 {
        let compass = localizer
            .update_compass_with_variance(truth.theta, 0.1_f64.to_radians().powi(2))
            .unwrap();
        assert!(compass.outcome.accepted);
        localizer
            .update_scan(&scan(&ranges(&truth, &walls(), &mut rng)))
            .unwrap();
    }
    let heading_error = angle_diff(localizer.pose().theta, truth.theta).to_degrees();
    assert!(
        heading_error.abs() < 0.05,
        "heading off by {heading_error}°"
    );
    let position_error = (localizer.pose().to_vector() - truth.to_vector())
        .xy()
        .norm();
    assert!(position_error < 0.002, "position off by {position_error} m");
    for (before, after) in placed.segments.iter().zip(&localizer.map().segments) {
        let turned = angle_diff(after.line.beta, before.line.beta).to_degrees();
        assert!((turned + 2.0).abs() < 0.05, "wall turned by {turned}°");
    }
    // Turned about the robot's position, where it stood when it placed them.
    let p = truth.to_vector().xy();
    let distance = |s: &lrf_lines::MapSegment| {
        (s.line.rho
            - p.dot(&nalgebra::Vector2::new(
                s.line.beta.cos(),
                s.line.beta.sin(),
            )))
        .abs()
    };
    for (before, after) in placed.segments.iter().zip(&localizer.map().segments) {
        assert!((distance(before) - distance(after)).abs() < 0.002);
    }
}
