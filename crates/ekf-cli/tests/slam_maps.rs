//! Maps without a reference (docs/maps.md): `ekf replay --grow-map` and `ekf map build
//! --slam` on the simulated two-rooms floor (a first room, an 8 m corridor, a second room,
//! and back), and `--slam` on the real freiburg-101, csail, seattle, infinite-corridor and
//! freiburg-campus CARMEN logs.
//!
//! Measured (docs/maps.md): two-rooms seed 1, paper-robot configuration, growing the
//! first-scan map: 0.034 m position RMSE over the whole run (the target is 0.05 m); the
//! first scan's map alone covers room A only. `--slam` on seed 2: 0.011 m after a rigid
//! alignment, 14 loop closures. freiburg-101 `--slam` with the defaults: 0.092 m, 17
//! closures (target 0.15 m).

mod import_common;

use ekf_cli::commands::evaluate::load_trajectory;
use ekf_cli::commands::import::{import_log, LogFormat};
use ekf_cli::commands::map::{build_map, MapSource};
use ekf_cli::config::Config;
use ekf_cli::eval::{ape, AlignMode, AlignmentOptions, ApeOptions};
use ekf_cli::import::CarmenOptions;
use ekf_cli::replay::{replay, Mode, ReplayOptions};
use ekf_cli::sim::simulate::{load_scenario, run_simulation, SimulateOptions};
use ekf_cli::slam::build_slam_map;
use ekf_cli::trajectory::Trajectory;
use ekf_ros::map_compare::CompareParams;
use ekf_ros::map_search::aligned_comparison;
use import_common::shared_data;
use std::path::{Path, PathBuf};

/// Simulates the two-rooms floor with `seed` into `dir`.
fn two_rooms(dir: &Path, seed: u64) -> PathBuf {
    let options = SimulateOptions {
        seed,
        ..SimulateOptions::default()
    };
    let scenario = load_scenario("two-rooms", &options).unwrap();
    let bag = dir.join(format!("two-rooms-{seed}.mcap"));
    run_simulation(&scenario, &options, Some(&bag)).unwrap();
    bag
}

/// Position RMSE (m) of `estimate` against the bag's reference, rigidly aligned (as
/// `evo_ape -a`).
fn aligned_rmse(estimate: &Trajectory, bag: &Path) -> f64 {
    let reference = load_trajectory(bag, None).unwrap();
    let options = ApeOptions {
        alignment: AlignmentOptions {
            mode: AlignMode::Rigid,
            n_to_align: None,
        },
        ..ApeOptions::default()
    };
    ape(&reference, estimate, &options)
        .unwrap()
        .summary
        .translation_m
        .rmse
}

#[test]
fn a_grown_map_keeps_the_filter_localized_through_the_corridor_and_the_second_room() {
    let dir = tempfile::tempdir().unwrap();
    let bag = two_rooms(dir.path(), 1);
    let config = Config::preset("paper-robot").unwrap();
    let run = |grow_map| {
        let options = ReplayOptions {
            mode: Mode::LaserCompass,
            init_from_truth: true,
            keep_trajectories: true,
            grow_map,
            ..ReplayOptions::default()
        };
        replay(&bag, &config, &options, &mut |_, _| {}).unwrap()
    };
    let (first_scan, grown) = (run(false), run(true));
    // The first scan sees room A only; the grown map reaches room B (x > 14 m).
    let reach = |map: &lrf_lines::LineMap| {
        map.segments
            .iter()
            .map(|s| s.start.x.max(s.end.x))
            .fold(f64::MIN, f64::max)
    };
    assert!(reach(&first_scan.map) < 14.0, "{}", reach(&first_scan.map));
    assert!(reach(&grown.map) > 19.0, "{}", reach(&grown.map));
    let accuracy = grown.summary.accuracy.as_ref().unwrap();
    assert!(
        accuracy.position_rmse_m <= 0.05,
        "grown map: {} m",
        accuracy.position_rmse_m
    );
    assert_eq!(grown.summary.tracking.losses, 0);
}

#[test]
fn slam_on_the_two_rooms_floor_closes_its_loops_and_tracks_within_five_centimetres() {
    let dir = tempfile::tempdir().unwrap();
    let bag = two_rooms(dir.path(), 2);
    let config = Config::preset("paper-robot").unwrap();
    let outcome = build_slam_map(&bag, &config, &mut |_, _| {}).unwrap();
    assert!(outcome.failure.is_none());
    let s = &outcome.summary;
    assert!(s.loops.closures >= 3, "{s:?}");
    assert_eq!(s.scans, 1501, "every scan has a corrected pose");
    let rmse = aligned_rmse(&outcome.trajectory, &bag);
    assert!(rmse <= 0.05, "{rmse} m");
    // Every wall of the floor is in the map, and the map has few more segments than
    // the floor has walls (no doubled walls).
    let floor = ekf_cli::sim::Room::two_rooms().to_map();
    assert!(
        outcome.map.len() <= 2 * floor.len(),
        "{} segments for {} walls",
        outcome.map.len(),
        floor.len()
    );
}

/// The shared CARMEN log `name` (`carmen/NAME-corrected.log.gz`) imported into `dir`.
fn carmen_bag(dir: &Path, name: &str) -> PathBuf {
    let bag = dir.join(format!("{name}.mcap"));
    import_log(
        &shared_data(&format!("carmen/{name}-corrected.log.gz")),
        &bag,
        LogFormat::Carmen(CarmenOptions::default()),
    )
    .unwrap();
    bag
}

/// `--slam` with the defaults on `bag`: the outcome and the trajectory's aligned position
/// RMSE against the log's reference.
fn slam_on_bag(bag: &Path) -> (ekf_cli::slam::SlamOutcome, f64) {
    let outcome = build_slam_map(bag, &Config::default(), &mut |_, _| {}).unwrap();
    assert!(outcome.failure.is_none());
    let rmse = aligned_rmse(&outcome.trajectory, bag);
    (outcome, rmse)
}

/// [`slam_on_bag`] on the shared CARMEN log `name`.
fn slam_on_carmen_log(name: &str) -> (ekf_cli::slam::SlamOutcome, f64) {
    let dir = tempfile::tempdir().unwrap();
    slam_on_bag(&carmen_bag(dir.path(), name))
}

#[test]
fn slam_on_freiburg_101_without_its_reference() {
    let (outcome, rmse) = slam_on_carmen_log("freiburg-101");
    assert!(outcome.summary.loops.closures >= 5, "{:?}", outcome.summary);
    assert!(rmse <= 0.15, "{rmse} m");
}

#[test]
fn slam_on_csail_finds_the_heading_its_odometry_loses_in_fast_turns() {
    // csail starts by turning 40° and more between scans, where its odometry errs by up
    // to 17°; the scans are aligned from every turn within 3σ of the predicted heading.
    // Measured: 0.148 m (0.474 m when aligned from the filter's and the predicted pose
    // only).
    let dir = tempfile::tempdir().unwrap();
    let bag = carmen_bag(dir.path(), "csail");
    let (outcome, rmse) = slam_on_bag(&bag);
    assert!(rmse <= 0.25, "{rmse} m");
    // Its map is turned 9.9° from the reference's frame, at the edge of the comparison's
    // ICP's reach from the identity (0.3 % matched from there); the comparison also
    // starts from the coarse transform of the two maps. Measured: 60 % matched.
    let (reference, _) = build_map(
        &bag,
        &Config::default(),
        MapSource::Reference(Default::default()),
    )
    .unwrap();
    let compared = aligned_comparison(&outcome.map, &reference, &CompareParams::default());
    assert!(compared.matched_share >= 0.5, "{compared:?}");
}

#[test]
fn slam_on_seattle_follows_the_turn_its_odometry_missed() {
    // Seattle's odometry is silent for 3.2 s at 1342 s while the robot turns 78°; the
    // scan after that gap is found by aligning it from every turn of the prediction.
    // Measured: 0.045 m (2.65 m when the first 26 scans stayed 80° off the rest).
    let (_, rmse) = slam_on_carmen_log("seattle");
    assert!(rmse <= 0.10, "{rmse} m");
}

/// The distance (m) the trajectory puts between its samples nearest `from` and `to` (s).
fn travelled_between(trajectory: &Trajectory, from: f64, to: f64) -> f64 {
    let at = |t: f64| {
        let t_ns = (t * 1e9) as i64;
        trajectory
            .iter()
            .min_by_key(|s| (s.t_ns as i64 - t_ns).abs())
            .unwrap()
            .pose
    };
    let (a, b) = (at(from), at(to));
    (b.x - a.x).hypot(b.y - a.y)
}

#[test]
fn slam_on_infinite_corridor_moves_with_the_robot_and_refuses_a_door_for_the_next() {
    // Between 519.9 and 523.1 s the robot drives 4.15 m along a corridor (reference and
    // odometry agree). A Gauss–Newton step of the scan alignment once jumped 1 m back
    // there, to a pose that fewer points fit than its start, and the map stood still for
    // four scans (0.72 m in all); the alignment now keeps its start in that case. At
    // 1117 s a closure matched the corridor 4.1 m along itself, and its next key scans
    // confirmed it; the graph refuses it (χ² 82 against 16.3). Measured: 4.1 m between
    // the two scans, aligned RMSE 1.97 m (2.37 m before both changes).
    let (outcome, rmse) = slam_on_carmen_log("infinite-corridor");
    let travelled = travelled_between(&outcome.trajectory, 519.9, 523.1);
    assert!((3.8..=4.5).contains(&travelled), "{travelled} m");
    assert!(
        outcome.summary.loops.inconsistent >= 1,
        "{:?}",
        outcome.summary
    );
    assert!(rmse <= 2.2, "{rmse} m");
}

#[test]
fn slam_on_freiburg_campus_searches_as_far_as_its_long_loops_drift() {
    // Outdoors, with loops of several hundred metres: the closures it needs are more than
    // 20 m from where the front end has the robot, beyond a 10 m search radius (16.2 m
    // aligned RMSE with one); the graph's consistency test, not the radius, keeps wrong
    // ones out. Measured: 1.36 m.
    let (_, rmse) = slam_on_carmen_log("freiburg-campus");
    assert!(rmse <= 3.0, "{rmse} m");
}

#[test]
fn a_log_that_breaks_off_is_mapped_up_to_the_damage_and_the_damage_is_reported() {
    let dir = tempfile::tempdir().unwrap();
    let whole =
        std::fs::read(PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../testdata/aces.mcap"))
            .unwrap();
    let bag = dir.path().join("truncated.mcap");
    std::fs::write(&bag, &whole[..whole.len() / 2]).unwrap();
    let outcome = build_slam_map(&bag, &Config::default(), &mut |_, _| {}).unwrap();
    let failure = outcome.failure.expect("the damage is reported").to_string();
    assert!(
        failure.contains("truncated.mcap") && failure.contains("byte"),
        "{failure}"
    );
    // What came before the damage is mapped: about half the scans, every one with a pose.
    let s = &outcome.summary;
    assert!((150..=290).contains(&s.scans), "{s:?}");
    assert_eq!(outcome.trajectory.len(), s.scans);
    assert!(outcome.map.len() > 50, "{}", outcome.map.len());
}

#[test]
fn growing_a_given_map_or_a_global_search_is_refused() {
    let bag = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../testdata/aces.mcap");
    let map = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../testdata/aces-map.json");
    for (map, global) in [(Some(map.clone()), false), (Some(map), true)] {
        let options = ReplayOptions {
            mode: Mode::Laser,
            map,
            global,
            grow_map: true,
            ..ReplayOptions::default()
        };
        let e = replay(&bag, &Config::default(), &options, &mut |_, _| {}).unwrap_err();
        assert!(
            e.to_string()
                .contains("--grow-map grows the first scan's map"),
            "{e}"
        );
    }
}
