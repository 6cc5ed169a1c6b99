//! End to end over pseudo-terminals: `ekf emulate` (the simulated paper robot served
//! through the device emulators) ↔ `ekf live --record`; `ekf replay` of the recording
//! gives the same poses bit for bit, and the live estimate tracks the emulator's ground
//! truth as closely as issue 5 asks of the same scenario in simulation (laser + compass:
//! position RMSE ≤ 2 cm, heading RMSE ≤ 0.3°).

mod live_support;

use ekf_cli::commands::evaluate::{evaluate, load_trajectory};
use ekf_cli::trajectory::Trajectory;
use ekf_core::{angle_diff, Pose2};
use live_support::{assert_replay_gives_the_same_poses, ekf, messages};
use std::fs::File;
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdout, Command, Stdio};
use std::time::{Duration, Instant};

/// Seconds the robot drives.
const DURATION_S: &str = "25";

/// A child process ended (SIGTERM, then waited for) when the test ends early.
struct Running(Child);

impl Running {
    fn terminate(&mut self) {
        let _ = Command::new("kill")
            .args(["-TERM", &self.0.id().to_string()])
            .status();
    }

    /// Waits for the process to exit by itself within `limit`.
    fn wait(&mut self, limit: Duration, what: &str) -> std::process::ExitStatus {
        let deadline = Instant::now() + limit;
        loop {
            if let Some(status) = self.0.try_wait().unwrap() {
                return status;
            }
            assert!(
                Instant::now() < deadline,
                "{what} did not end within {limit:?}"
            );
            std::thread::sleep(Duration::from_millis(50));
        }
    }
}

impl Drop for Running {
    fn drop(&mut self) {
        if matches!(self.0.try_wait(), Ok(None)) {
            self.terminate();
            let _ = self.0.wait();
        }
    }
}

/// The `name: value` lines `ekf emulate` prints before it runs, up to `run:`.
fn device_paths(out: ChildStdout) -> (Vec<(String, PathBuf)>, BufReader<ChildStdout>) {
    let mut reader = BufReader::new(out);
    let mut paths = Vec::new();
    loop {
        let mut line = String::new();
        assert!(
            reader.read_line(&mut line).unwrap() > 0,
            "ekf emulate ended early"
        );
        let (name, value) = line.trim_end().split_once(": ").unwrap();
        if name == "run" {
            return (paths, reader);
        }
        paths.push((name.to_owned(), PathBuf::from(value)));
    }
}

/// Log times of `topic` in a bag.
fn stamps(path: &Path, topic: &str) -> Vec<u64> {
    messages(path, topic).into_iter().map(|(t, _)| t).collect()
}

/// The true pose at `t_ns`, interpolated linearly between the truth's samples.
fn truth_at(truth: &Trajectory, t_ns: u64) -> Option<Pose2<f64>> {
    let s = &truth.samples;
    let i = s.partition_point(|p| p.t_ns <= t_ns);
    if i == 0 || i == s.len() {
        return None;
    }
    let (a, b) = (&s[i - 1], &s[i]);
    let f = (t_ns - a.t_ns) as f64 / (b.t_ns - a.t_ns) as f64;
    Some(Pose2::new(
        a.pose.x + f * (b.pose.x - a.pose.x),
        a.pose.y + f * (b.pose.y - a.pose.y),
        a.pose.theta + f * angle_diff(b.pose.theta, a.pose.theta),
    ))
}

#[test]
fn live_against_the_emulated_robot_replays_bit_for_bit_and_tracks_the_truth() {
    let dir = tempfile::tempdir().unwrap();
    let truth_path = dir.path().join("truth.mcap");
    let recording = dir.path().join("live.mcap");
    let mut emulate = Running(
        ekf()
            .args(["emulate", "--scenario", "paper", "--seed", "1", "--json"])
            .args(["--duration", DURATION_S, "--truth"])
            .arg(&truth_path)
            .arg("--dir")
            .arg(dir.path().join("dev"))
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap(),
    );
    let (paths, mut emulate_out) = device_paths(emulate.0.stdout.take().unwrap());
    let path = |name: &str| &paths.iter().find(|p| p.0 == name).unwrap().1;
    let mut live = Running(
        ekf()
            .args(["live", "--json", "--laser"])
            .arg(path("laser"))
            .arg("--base")
            .arg(path("base"))
            .arg("--gps")
            .arg(path("gps"))
            .arg("--config")
            .arg(path("config"))
            .arg("--record")
            .arg(&recording)
            .stdout(File::create(dir.path().join("live.out")).unwrap())
            .stderr(File::create(dir.path().join("live.err")).unwrap())
            .spawn()
            .unwrap(),
    );

    // The emulator ends by itself once the robot has driven its 25 s.
    let status = emulate.wait(Duration::from_secs(120), "ekf emulate");
    let mut summary = String::new();
    emulate_out.read_line(&mut summary).unwrap();
    assert!(status.success(), "ekf emulate: {summary}");
    let summary: serde_json::Value = serde_json::from_str(&summary).unwrap();
    assert_eq!(summary["steps"], 250, "{summary}");
    assert_eq!(summary["interrupted"], false, "{summary}");
    live.terminate();
    let status = live.wait(Duration::from_secs(60), "ekf live after SIGTERM");
    let live_err = std::fs::read_to_string(dir.path().join("live.err")).unwrap();
    assert!(status.success(), "{live_err}");
    let live_out = std::fs::read_to_string(dir.path().join("live.out")).unwrap();
    let live_summary: serde_json::Value =
        serde_json::from_str(live_out.lines().last().unwrap()).unwrap();
    // Indoors the GPS answers without a fix; the filter fused lines and headings.
    assert_eq!(live_summary["gps_fixes"], 0, "{live_summary}");
    assert!(live_summary["devices"]["gps"]["no_fix"].as_u64().unwrap() > 10);
    let filter = &live_summary["filter"];
    assert!(filter["lines"]["fused"].as_u64().unwrap() > 200, "{filter}");
    assert!(
        filter["compass"]["accepted"].as_u64().unwrap() > 200,
        "{filter}"
    );

    // `ekf replay` of the recording: the same poses, bit for bit.
    let replayed = dir.path().join("replayed.mcap");
    // The emulator leaves its live.toml in a folder it was given: the replay uses it.
    let config = path("config");
    assert_replay_gives_the_same_poses(
        &recording,
        &replayed,
        &["--config".as_ref(), config.as_os_str()],
        600,
    );

    // Accuracy as issue 5 measures it in simulation: the estimate once each 0.1 s
    // step's measurements are fused (the pose after the step's compass reading), against
    // the true pose at that instant.
    let truth = load_trajectory(&truth_path, None).unwrap();
    let estimate = load_trajectory(&recording, None).unwrap();
    let compass = stamps(&recording, "/compass");
    let (mut sq_pos, mut sq_head, mut n) = (0.0, 0.0, 0usize);
    for p in estimate
        .iter()
        .filter(|p| compass.binary_search(&p.t_ns).is_ok())
    {
        if let Some(t) = truth_at(&truth, p.t_ns) {
            sq_pos += (p.pose.x - t.x).powi(2) + (p.pose.y - t.y).powi(2);
            sq_head += angle_diff(p.pose.theta, t.theta).powi(2);
            n += 1;
        }
    }
    assert!(n > 200, "{n} poses within the truth");
    let (pos_rmse, head_rmse) = (
        (sq_pos / n as f64).sqrt(),
        (sq_head / n as f64).sqrt().to_degrees(),
    );
    // Every pose, as `ekf evaluate LIVE.mcap --truth TRUTH.mcap` pairs them.
    let report = evaluate(&estimate, &truth, false).unwrap();
    eprintln!(
        "after each step: {n} poses, position RMSE {pos_rmse:.4} m, heading RMSE {head_rmse:.3}°; \
         ekf evaluate (every pose): {} matched, position RMSE {:.4} m, heading RMSE {:.3}°",
        report.ape.matched_poses, report.ape.translation_m.rmse, report.ape.heading_error_deg.rmse
    );
    assert!(pos_rmse <= 0.02, "position RMSE {pos_rmse} m");
    assert!(head_rmse <= 0.3, "heading RMSE {head_rmse}°");
    assert!(report.ape.matched_poses > 600, "{:?}", report.ape);
    assert!(report.ape.translation_m.rmse <= 0.02, "{:?}", report.ape);

    // The poses it printed as it ran: at most one per wheel reading, later each than the
    // one before, predicted from the fused state (held back ~0.3 s for the laser) through
    // the wheel readings since, and as accurate at their own time as the fused ones.
    let printed: Vec<serde_json::Value> = live_out
        .lines()
        .filter(|l| l.contains("\"theta\""))
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    let wheel_stamps = stamps(&recording, "/joint_states");
    assert!(printed.len() <= wheel_stamps.len());
    let (mut leads, mut previous): (Vec<u64>, u64) = (Vec::new(), 0);
    let (mut sq, mut n) = (0.0, 0usize);
    for p in &printed {
        let (t, fused) = (p["t_ns"].as_u64().unwrap(), p["fused_ns"].as_u64().unwrap());
        // A fused motion step first: no pose from before the recording's first wheel
        // reading, and none more than a second behind.
        assert!(fused >= wheel_stamps[0] && t > previous, "{p}");
        assert!(t - fused < 1_000_000_000, "{p}");
        previous = t;
        leads.push(t - fused);
        // Before the robot moves off, the truth has not started.
        if let Some(truth) = truth_at(&truth, t) {
            sq += (p["x"].as_f64().unwrap() - truth.x).powi(2)
                + (p["y"].as_f64().unwrap() - truth.y).powi(2);
            n += 1;
        }
    }
    assert!(
        n > 200,
        "{n} of {} printed poses within the truth",
        printed.len()
    );
    leads.sort_unstable();
    let median_lead_s = leads[leads.len() / 2] as f64 * 1e-9;
    let printed_rmse = (sq / n as f64).sqrt();
    eprintln!(
        "printed: {} poses, median {median_lead_s:.3} s ahead of the fused state, position RMSE {printed_rmse:.4} m over {n}",
        printed.len()
    );
    assert!(median_lead_s > 0.1, "median lead {median_lead_s} s");
    assert!(printed_rmse <= 0.02, "printed poses' RMSE {printed_rmse} m");
}
