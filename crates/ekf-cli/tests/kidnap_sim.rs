//! Kidnapping in simulation: in the L-shaped room (`ekf simulate --scenario l-room`), the
//! robot is carried 2 m to its left and turned a quarter turn between two scans, its
//! wheels still; the encoders see nothing. Replayed laser-only against the room's map
//! from the first true pose, the filter must notice, relocalize from the laser and track
//! again within 10 scans, with no wrong relocalization.

use ekf_cli::config::Config;
use ekf_cli::replay::{replay, Mode, ReplayOptions, ReplayOutcome};
use ekf_cli::sim::{LogRecorder, Scenario, Simulator};
use ekf_core::Pose2;
use nalgebra::Point2;
use std::f64::consts::FRAC_PI_2;
use std::path::Path;

/// When the robot is carried (s): on the room's first long edge, heading east.
const KIDNAP_S: f64 = 12.0;

/// Where it is put down, in its own frame: 2 m to the left, turned 90°.
fn carry() -> Pose2<f64> {
    Pose2::new(0.0, 2.0, FRAC_PI_2)
}

/// Simulates 40 s of the l-room scenario with the kidnapping into `dir`, and replays it;
/// returns the outcome and the time of the kidnapping (ns).
fn run(dir: &Path) -> (ReplayOutcome, u64) {
    let mut scenario = Scenario::builtin("l-room").unwrap();
    scenario.duration_s = 40.0;
    let seed = 7;
    let bag = dir.join("kidnapped.mcap");
    let mut recorder = LogRecorder::create(&bag, &scenario, seed).unwrap();
    let mut sim = Simulator::new(&scenario, seed);
    let kidnap_step = (KIDNAP_S / scenario.dt).round() as u64;
    let mut kidnap_ns = 0;
    for k in 0..=scenario.steps() {
        if k > 0 {
            let truth = sim.pose();
            sim.advance(&truth);
        }
        if k == kidnap_step {
            let before = sim.pose();
            assert!(before.y < 1.5 && before.theta.cos() > 0.9, "{before:?}");
            let after = before.compose(&carry());
            let clearance = scenario.room.clearance(&Point2::new(after.x, after.y));
            assert!(clearance > 0.5, "put down in the room: {after:?}");
            sim.carry(&carry());
        }
        let sample = sim.measure();
        if k == kidnap_step {
            kidnap_ns = sample.t_ns;
        }
        recorder.record(&sample).unwrap();
    }
    recorder.finish().unwrap();
    let map = dir.join("room.json");
    std::fs::write(&map, scenario.room.to_map().to_json().unwrap()).unwrap();
    let options = ReplayOptions {
        mode: Mode::Laser,
        map: Some(map),
        init_from_truth: true,
        keep_trajectories: true,
        ..ReplayOptions::default()
    };
    let config = Config::preset("paper-robot").unwrap();
    let outcome = replay(&bag, &config, &options, &mut |_, _| {}).unwrap();
    assert!(outcome.failure.is_none());
    (outcome, kidnap_ns)
}

#[test]
fn a_robot_carried_between_two_scans_is_found_again() {
    let dir = tempfile::tempdir().unwrap();
    let (outcome, kidnap_ns) = run(dir.path());
    let t = &outcome.summary.tracking;
    eprintln!("{t:?}");
    // Position errors at the scans (the reference poses at scan times).
    let est: Vec<_> = outcome.trajectory.iter().collect();
    let scan_errors: Vec<(u64, f64)> = outcome
        .reference
        .iter()
        .filter_map(|r| {
            let j = est.partition_point(|p| p.t_ns <= r.t_ns);
            let p = est.get(j.checked_sub(1)?)?;
            Some((r.t_ns, (p.pose.x - r.pose.x).hypot(p.pose.y - r.pose.y)))
        })
        .collect();
    let before: Vec<f64> = scan_errors
        .iter()
        .filter(|e| e.0 < kidnap_ns)
        .map(|e| e.1)
        .collect();
    assert!(
        before.iter().all(|&e| e < 0.1),
        "tracking before: {before:?}"
    );
    // Relocalized, and every relocalization after the kidnapping: none before it.
    assert!(t.relocalizations >= 1, "{t:?}");
    let first = t.first_relocalizations_ns[0];
    assert!(first >= kidnap_ns, "{t:?}");
    assert_eq!(t.lost_at_end, 0);
    // Found within 10 scans: the scans of the laser's period after the kidnapping.
    let scan_period_ns = {
        let scenario = Scenario::builtin("l-room").unwrap();
        (scenario.dt * 1e9).round() as u64 * u64::from(scenario.laser.period_steps.max(1))
    };
    assert!(
        first - kidnap_ns <= 10 * scan_period_ns,
        "relocalized {} scans after the kidnapping",
        (first - kidnap_ns) / scan_period_ns
    );
    // From then on the filter tracks: every pose within 0.1 m.
    let after: Vec<f64> = scan_errors
        .iter()
        .filter(|e| e.0 >= first)
        .map(|e| e.1)
        .collect();
    assert!(after.len() > 100, "{} poses after", after.len());
    let worst = after.iter().copied().fold(0.0, f64::max);
    assert!(
        worst < 0.1,
        "worst error after the relocalization: {worst} m"
    );
}
