//! `ekf live` against the device emulators on pseudo-terminals: faults are counted and
//! never fused, a replugged laser is reconnected, SIGTERM finishes the recording, and
//! `ekf replay` of the recording gives the same poses bit for bit. A silent device is an
//! error naming its port.

mod live_support;

use ekf_cli::devices::sick::device::Sweep;
use ekf_cli::devices::sick::RangeUnit;
use ekf_cli::emulate::{Device, Emulators, Fault, RobotSample};
use ekf_cli::mcap_io::BagReader;
use live_support::{assert_replay_gives_the_same_poses, ekf, live_on, start_emulators, still};
use std::f64::consts::{FRAC_PI_2, TAU};
use std::path::PathBuf;
use std::process::Command;
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

const ROOM: (f64, f64) = (8.0, 6.0);
const TICKS_PER_REV: f64 = 500.0;
const WHEEL_RADIUS: f64 = 0.05;
const TRACK: f64 = 0.6;

/// A robot driving a gentle arc in a rectangular room, with exact encoder ticks.
struct Robot {
    x: f64,
    y: f64,
    theta: f64,
    phi_left: f64,
    phi_right: f64,
    t_ns: u64,
    /// Turn rate (rad/s).
    w: f64,
}

impl Robot {
    fn new() -> Self {
        Self {
            x: 2.0,
            y: 2.0,
            theta: 0.3,
            phi_left: 0.0,
            phi_right: 0.0,
            t_ns: 0,
            w: 0.1,
        }
    }

    /// Advances by `dt` at 0.25 m/s and the turn rate.
    fn step(&mut self, dt: f64) {
        let (v, w) = (0.25, self.w);
        self.phi_left += (v - w * TRACK / 2.0) / WHEEL_RADIUS * dt;
        self.phi_right += (v + w * TRACK / 2.0) / WHEEL_RADIUS * dt;
        let mid = self.theta + w * dt / 2.0;
        self.x += v * dt * mid.cos();
        self.y += v * dt * mid.sin();
        self.theta += w * dt;
        self.t_ns += (dt * 1e9) as u64;
    }

    fn range(&self, bearing: f64) -> f64 {
        let a = self.theta + bearing;
        let (c, s) = (a.cos(), a.sin());
        let mut best = f64::INFINITY;
        for (d, wall) in [
            (c, ROOM.0 - self.x),
            (-c, self.x),
            (s, ROOM.1 - self.y),
            (-s, self.y),
        ] {
            if d > 1e-9 {
                best = best.min(wall / d);
            }
        }
        best
    }

    fn sample(&self, with_scan: bool) -> RobotSample {
        // Counters start near 2³² so they wrap during the run.
        let ticks = |phi: f64| {
            (u32::MAX - 200).wrapping_add((phi / TAU * TICKS_PER_REV).round() as i64 as u32)
        };
        let sweep = with_scan.then(|| Sweep {
            angle_min: -FRAC_PI_2,
            angle_increment: 0.5f64.to_radians(),
            ranges: (0..361)
                .map(|i| self.range(-FRAC_PI_2 + (i as f64 * 0.5).to_radians()))
                .collect(),
        });
        RobotSample {
            t_ns: self.t_ns,
            left_ticks: ticks(self.phi_left),
            right_ticks: ticks(self.phi_right),
            bearing_deg: (90.0 - self.theta.to_degrees()).rem_euclid(360.0),
            sweep,
            motion: None,
            gps: None,
        }
    }
}

/// Sends `ekf live` `signal` (`kill`'s spelling, e.g. `-TERM`) and waits for it to end.
fn stop(mut live: std::process::Child, signal: &str) -> std::process::ExitStatus {
    let status = Command::new("kill")
        .args([signal, &live.id().to_string()])
        .status()
        .unwrap();
    assert!(status.success());
    let deadline = Instant::now() + Duration::from_secs(60);
    while live.try_wait().unwrap().is_none() {
        assert!(
            Instant::now() < deadline,
            "ekf live did not stop on kill {signal}"
        );
        std::thread::sleep(Duration::from_millis(50));
    }
    live.wait().unwrap()
}

#[test]
fn faults_reconnect_sigterm_and_bit_identical_replay() {
    // 9 s of driving, paced in real time at 10 Hz; the laser sweeps at 5 Hz. The robot
    // waits at its start (k = 0) while the devices come up.
    let mut robot = Robot::new();
    let run = run_live(RangeUnit::Millimetres, 90, |k, emulators| {
        if k > 0 {
            robot.step(0.1);
        }
        emulators.sample(robot.sample(k % 2 == 0));
        match k {
            20 => emulators.fault(Device::Laser, Fault::Disconnect(Duration::from_millis(600))),
            55 => emulators.fault(Device::Laser, Fault::Garbage(50)),
            59 => emulators.fault(Device::Laser, Fault::Truncate),
            63 => emulators.fault(Device::Laser, Fault::BadChecksum),
            65 => emulators.fault(Device::Base, Fault::Exception(4)),
            67 => emulators.fault(Device::Base, Fault::BadChecksum),
            _ => {}
        }
    });
    let (stdout, stderr, recording) = (&run.stdout, &run.stderr, &run.recording);

    // The replug was reported and the laser came back.
    assert!(stderr.contains("reconnecting"), "{stderr}");
    assert!(stderr.contains("back:"), "{stderr}");

    // The summary (last line) counts the faults.
    let summary = run.summary();
    let laser = &summary["devices"]["laser"];
    assert!(laser["garbage_bytes"].as_u64().unwrap() >= 50, "{summary}");
    assert!(laser["truncated"].as_u64().unwrap() >= 1, "{summary}");
    assert!(laser["bad_crc"].as_u64().unwrap() >= 1, "{summary}");
    let base = &summary["devices"]["base"];
    assert_eq!(base["exceptions"].as_u64(), Some(1), "{summary}");
    assert_eq!(base["bad_crc"].as_u64(), Some(1), "{summary}");
    assert!(
        summary["reconnects"]["laser"].as_u64().unwrap() >= 1,
        "{summary}"
    );
    assert!(
        summary["filter"]["lines"]["fused"].as_u64().unwrap() > 10,
        "{summary}"
    );

    // The estimate follows the robot (faults were not fused).
    let last: serde_json::Value = serde_json::from_str(
        stdout
            .lines()
            .rev()
            .find(|l| l.contains("\"theta\""))
            .unwrap(),
    )
    .unwrap();
    // The filter starts at the origin with heading 0, but the compass says 17° and the
    // initial covariance allows 1°. The compass's gate rejects it until its lock-out
    // recovery fuses the consistent readings: the estimate ends in the compass's frame,
    // about the start position.
    let (ex, ey) = (robot.x - 2.0, robot.y - 2.0);
    let (x, y) = (last["x"].as_f64().unwrap(), last["y"].as_f64().unwrap());
    assert!(
        ((x - ex).powi(2) + (y - ey).powi(2)).sqrt() < 0.3,
        "estimate ({x}, {y}), truth ({ex}, {ey})"
    );
    let theta = last["theta"].as_f64().unwrap();
    assert!(
        ekf_core::angle_diff(theta, robot.theta).abs() < 3.0_f64.to_radians(),
        "estimate θ {theta}, truth {}",
        robot.theta
    );

    // The recording is complete and replays to the same poses, bit for bit.
    let replayed = recording.with_file_name("replayed.mcap");
    assert_replay_gives_the_same_poses(recording, &replayed, &[], 50);
}

#[test]
fn a_silent_laser_is_a_timeout_naming_the_port() {
    let dir = tempfile::tempdir().unwrap();
    let emulators = start_emulators(dir.path(), RangeUnit::Millimetres);
    emulators.fault(Device::Laser, Fault::Silence(Duration::from_secs(120)));
    let laser = emulators.path(Device::Laser);
    let out = ekf()
        .args(["live", "--laser"])
        .arg(&laser)
        .arg("--base")
        .arg(emulators.path(Device::Base))
        .output()
        .unwrap();
    emulators.stop();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        stderr.contains(&format!("laser on {}: timeout", laser.display())),
        "{stderr}"
    );
    assert!(
        stderr.contains("expected an ACK (06) and an A0 reply"),
        "{stderr}"
    );
}

/// What a run of `ekf live --record --json` against the emulators left.
struct LiveRun {
    _dir: tempfile::TempDir,
    recording: PathBuf,
    /// When the signal was sent (ns since the epoch, the recording's clock).
    stopped_ns: u64,
    stdout: String,
    stderr: String,
}

impl LiveRun {
    /// The summary (the last line of the JSON output).
    fn summary(&self) -> serde_json::Value {
        serde_json::from_str(self.stdout.lines().last().unwrap()).unwrap()
    }

    /// The recorded messages of `topic` as `T`.
    fn messages<T: ekf_cli::ros2::RosMessage>(&self, topic: &str) -> Vec<T> {
        BagReader::open(&self.recording)
            .unwrap()
            .messages()
            .unwrap()
            .map(Result::unwrap)
            .filter(|m| m.topic() == topic)
            .map(|m| m.decode_as::<T>().unwrap())
            .collect()
    }
}

/// Runs `ekf live` on emulators whose laser sends `unit`; `step(k, emulators)` is called
/// for k = 0..steps at 10 Hz (real time) once the devices are up, then `ekf live` gets
/// SIGTERM.
fn run_live(unit: RangeUnit, steps: u32, step: impl FnMut(u32, &Emulators)) -> LiveRun {
    run_live_until(unit, steps, "-TERM", step)
}

/// As [`run_live`], ending `ekf live` with `signal` (`kill`'s spelling, e.g. `-INT`),
/// after which it must exit 0.
fn run_live_until(
    unit: RangeUnit,
    steps: u32,
    signal: &str,
    step: impl FnMut(u32, &Emulators),
) -> LiveRun {
    let (run, status) = drive_live(unit, steps, signal, step);
    assert!(status.success(), "stderr: {}", run.stderr);
    run
}

/// Starts `ekf live --record` on emulators whose laser sends `unit`, calls `step(k,
/// emulators)` for k = 0..steps at 10 Hz (real time) once the devices are up, then sends
/// `signal`. Returns the run and how `ekf live` exited.
fn drive_live(
    unit: RangeUnit,
    steps: u32,
    signal: &str,
    step: impl FnMut(u32, &Emulators),
) -> (LiveRun, std::process::ExitStatus) {
    drive_live_with(unit, steps, signal, &[], step)
}

/// As [`drive_live`], with further `ekf live` arguments.
fn drive_live_with(
    unit: RangeUnit,
    steps: u32,
    signal: &str,
    args: &[&str],
    mut step: impl FnMut(u32, &Emulators),
) -> (LiveRun, std::process::ExitStatus) {
    let dir = tempfile::tempdir().unwrap();
    let emulators = start_emulators(dir.path(), unit);
    let recording = dir.path().join("run.mcap");
    // Into files, not pipes: a pipe nobody reads fills up (64 kB, about 25 s of poses)
    // and then blocks `ekf live`.
    let (out_path, err_path) = (dir.path().join("stdout"), dir.path().join("stderr"));
    let mut live = live_on(&emulators, &recording)
        .args(args)
        .stdout(std::fs::File::create(&out_path).unwrap())
        .stderr(std::fs::File::create(&err_path).unwrap())
        .spawn()
        .unwrap();
    // The devices come up on samples: hold the first one until both are.
    let deadline = Instant::now() + Duration::from_secs(60);
    while !(emulators.ready(Device::Laser) && emulators.ready(Device::Base)) {
        assert!(
            Instant::now() < deadline,
            "ekf live did not bring the devices up"
        );
        assert!(live.try_wait().unwrap().is_none(), "ekf live ended early");
        step(0, &emulators);
        std::thread::sleep(Duration::from_millis(100));
    }
    let started = Instant::now();
    for k in 0..steps {
        step(k, &emulators);
        let due = started + Duration::from_millis(100 * u64::from(k + 1));
        std::thread::sleep(due.saturating_duration_since(Instant::now()));
    }
    let stopped_ns = epoch_ns();
    let status = stop(live, signal);
    emulators.stop();
    let run = LiveRun {
        recording,
        stopped_ns,
        stdout: std::fs::read_to_string(&out_path).unwrap(),
        stderr: std::fs::read_to_string(&err_path).unwrap(),
        _dir: dir,
    };
    (run, status)
}

fn epoch_ns() -> u64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .unwrap()
        .as_nanos() as u64
}

#[test]
fn sigint_finishes_the_recording() {
    let run = run_live_until(RangeUnit::Millimetres, 20, "-INT", |k, emulators| {
        emulators.sample(still(k, k % 2 == 0));
    });
    // A clean exit with the summary printed, and a finished file: every message reads
    // back without damage (the reader reports a cut-off file after its last message).
    assert!(
        run.summary()["filter"]["motion_steps"].as_u64().unwrap() > 5,
        "{}",
        run.stdout
    );
    let poses: Vec<ekf_cli::ros2::geometry_msgs::PoseWithCovarianceStamped> =
        run.messages("/ekf/pose");
    assert!(poses.len() > 5, "{}", poses.len());
    let scans: Vec<ekf_cli::ros2::sensor_msgs::LaserScan> = run.messages("/scan");
    assert!(!scans.is_empty());
}

#[test]
fn scans_are_stamped_when_they_were_measured() {
    // The emulated laser sends a sweep's telegram once it is complete, at 38400 baud
    // (0.19 s for 732 bytes): the stamp must be the sweep's, not the arrival's.
    let mut measured = Vec::new();
    let run = run_live(RangeUnit::Millimetres, 40, |k, emulators| {
        let with_scan = k % 2 == 0 && k > 0;
        if with_scan {
            measured.push((k, epoch_ns()));
        }
        emulators.sample(still(k, with_scan));
    });
    let scans: Vec<ekf_cli::ros2::sensor_msgs::LaserScan> = run.messages("/scan");
    let mut errors_ms: Vec<f64> = scans
        .iter()
        .filter_map(|scan| {
            let k = ((scan.ranges[0] - 1.0) * 1000.0).round() as u32;
            let (_, t) = measured.iter().find(|(j, _)| *j == k)?;
            let stamp = scan.header.stamp.to_nanos().unwrap();
            Some((stamp as f64 - *t as f64) * 1e-6)
        })
        .collect();
    assert!(errors_ms.len() >= 15, "{} scans matched", errors_ms.len());
    errors_ms.sort_by(f64::total_cmp);
    let median = errors_ms[errors_ms.len() / 2];
    eprintln!("scan stamp - sweep time (ms): median {median:.1}, all {errors_ms:.1?}");
    assert!(median.abs() < 40.0, "median {median} ms: {errors_ms:?}");
    assert_eq!(run.summary()["late_readings"], 0, "{}", run.stdout);
}

#[test]
fn a_power_cycled_base_controller_is_no_wheel_motion() {
    // The controller's counts stand at millions of ticks; it is unplugged, and comes back
    // power-cycled: counts and sample counter from 0.
    let mut robot = Robot::new();
    let mut restart: Option<(u32, u32)> = None;
    // When each robot step was handed to the emulators (ns since the epoch, the clock
    // `ekf live` stamps with).
    let mut stepped_at: Vec<u64> = Vec::new();
    let run = run_live(RangeUnit::Millimetres, 60, |k, emulators| {
        if k > 0 {
            robot.step(0.1);
            stepped_at.push(
                std::time::SystemTime::now()
                    .duration_since(std::time::UNIX_EPOCH)
                    .unwrap()
                    .as_nanos() as u64,
            );
        }
        let mut s = robot.sample(k % 2 == 0);
        let (left, right) = (s.left_ticks, s.right_ticks);
        match restart {
            None => {
                s.left_ticks = left.wrapping_add(3_000_000);
                s.right_ticks = right.wrapping_add(3_000_000);
            }
            Some((l0, r0)) => {
                s.left_ticks = left.wrapping_sub(l0);
                s.right_ticks = right.wrapping_sub(r0);
            }
        }
        emulators.sample(s);
        if k == 20 {
            emulators.fault(Device::Base, Fault::Disconnect(Duration::from_millis(300)));
            restart = Some((left, right));
        }
    });
    assert!(run.stderr.contains("base on"), "{}", run.stderr);
    let summary = run.summary();
    assert!(
        summary["reconnects"]["base"].as_u64().unwrap_or(0) >= 1,
        "{summary}"
    );
    // The robot moves one sample per test step (the right wheel, the faster, 0.56 rad);
    // `ekf live` polls at 10 Hz on its own clock, so a recorded step spans as many
    // samples as the test handed over between the two polls (a loaded host bunches
    // them), and one more of the interpolation towards the next. A power-cycled counter
    // read as a difference would be a step of thousands of radians, and motion invented
    // across the outage would show in the total, which cannot exceed what the wheels
    // turned.
    let joints: Vec<ekf_cli::ros2::sensor_msgs::JointState> = run.messages("/joint_states");
    let per_sample = {
        let mut one = Robot::new();
        one.step(0.1);
        one.phi_right
    };
    let tick = TAU / TICKS_PER_REV;
    let mut total = [0.0f64; 2];
    for w in joints.windows(2) {
        let (t0, t1) = (
            w[0].header.stamp.to_nanos().unwrap(),
            w[1].header.stamp.to_nanos().unwrap(),
        );
        let samples = stepped_at.iter().filter(|&&t| t0 < t && t <= t1).count();
        let possible = per_sample * (samples + 2) as f64;
        for (i, wheel_total) in total.iter_mut().enumerate() {
            let step = (w[1].position[i] - w[0].position[i]).abs();
            assert!(
                step <= possible,
                "a wheel stepped {step} rad while {samples} samples were handed over; \
                 {summary}"
            );
            *wheel_total += step;
        }
    }
    assert!(
        total[0] <= robot.phi_left + tick && total[1] <= robot.phi_right + tick,
        "recorded {total:?} rad, the wheels turned {:?}; {summary}",
        [robot.phi_left, robot.phi_right]
    );
    // The motion after the reconnection is tracked: the controller went away at sample
    // 20 of 60 for 0.3 s plus the reconnection (about 2 s in all), so about 65 % of the
    // motion is recorded; had tracking stopped there, a third would be.
    assert!(
        total[1] > 0.4 * robot.phi_right,
        "recorded {total:?} rad of {} turned; {summary}",
        robot.phi_right
    );
    assert!(
        joints.len() > 30,
        "{} joint states; {summary}",
        joints.len()
    );
    let after = summary["devices"]["base"]["replies"].as_u64().unwrap();
    assert!(after > 5, "{summary}");
}

#[test]
fn a_scanner_in_centimetres_keeps_its_long_ranges() {
    // In cm mode (the 80 m mode) a return at 9.5 m is a range like any other.
    let run = run_live(RangeUnit::Centimetres, 15, |k, emulators| {
        let mut s = still(k, k % 2 == 0);
        if let Some(sweep) = s.sweep.as_mut() {
            sweep.ranges.iter_mut().for_each(|r| *r = 9.5);
        }
        emulators.sample(s);
    });
    let scans: Vec<ekf_cli::ros2::sensor_msgs::LaserScan> = run.messages("/scan");
    assert!(scans.len() >= 5, "{} scans", scans.len());
    for scan in &scans {
        assert!(
            (scan.range_max - 81.82).abs() < 1e-3 && (scan.range_min - 0.01).abs() < 1e-6,
            "range_min {} range_max {}",
            scan.range_min,
            scan.range_max
        );
        assert!(scan.ranges.iter().all(|r| (r - 9.5).abs() < 1e-4));
    }
}

/// `kill -9` of `ekf live --record` after `seconds` of driving: the recording, which then
/// has no summary, opens, holds every message up to at most 2 s before the kill (its
/// chunks are closed and synced every second), and replays to the same point.
fn a_hard_kill_loses_at_most_the_last_two_seconds(seconds: u32) {
    let mut robot = Robot::new();
    let (run, status) = drive_live(RangeUnit::Millimetres, seconds * 10, "-KILL", |k, e| {
        if k > 0 {
            robot.step(0.1);
        }
        e.sample(robot.sample(k % 2 == 0));
    });
    assert!(!status.success(), "ekf live survived kill -9");
    let mut last_ns = 0;
    let mut joint_states = 0;
    for m in BagReader::open(&run.recording)
        .expect("a killed recording opens")
        .messages()
        .unwrap()
    {
        // The cut end is reported after the last intact message.
        let Ok(m) = m else { continue };
        last_ns = last_ns.max(m.log_time);
        joint_states += u64::from(m.topic() == "/joint_states");
    }
    let lost_s = (run.stopped_ns.saturating_sub(last_ns)) as f64 * 1e-9;
    eprintln!("kill -9 after {seconds} s: {joint_states} wheel readings kept, last {lost_s:.2} s before the kill lost");
    assert!(
        lost_s <= 2.0,
        "the last {lost_s:.2} s before the kill are lost"
    );
    assert!(
        joint_states >= u64::from(seconds) * 8,
        "{joint_states} wheel readings"
    );

    // The replay reads it to its last intact chunk, then names the cut (exit 1).
    let tum = run.recording.with_extension("tum");
    let replay = ekf()
        .args(["replay", "--json", "--tum"])
        .arg(&tum)
        .arg(&run.recording)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&replay.stderr);
    assert!(stderr.contains("truncated or corrupt MCAP"), "{stderr}");
    let text = std::fs::read_to_string(&tum).unwrap();
    let last_row_ns = text
        .lines()
        .filter(|l| !l.starts_with('#'))
        .filter_map(|l| l.split_whitespace().next()?.parse::<f64>().ok())
        .fold(0.0, f64::max)
        * 1e9;
    let replay_lost_s = (run.stopped_ns as f64 - last_row_ns) * 1e-9;
    assert!(
        replay_lost_s <= 2.0,
        "the replay ends {replay_lost_s:.2} s before the kill"
    );
}

#[test]
fn a_hard_kill_after_15_s_loses_at_most_the_last_two_seconds() {
    a_hard_kill_loses_at_most_the_last_two_seconds(15);
}

#[test]
fn a_hard_kill_after_70_s_loses_at_most_the_last_two_seconds() {
    a_hard_kill_loses_at_most_the_last_two_seconds(70);
}

/// Every device silent for 6 s while the robot drives on (the outage): the base
/// controller counted on meanwhile, and the motion it counted is kept when it answers
/// again, so the estimate is back within 5 cm of the truth within 5 s of the devices'
/// return (it was 1.40 m off for good when that motion was dropped).
#[test]
fn the_motion_of_a_6_s_outage_is_kept_and_the_estimate_is_back_within_5_s() {
    // A wide arc (5 m radius) that stays 0.2 m inside the room for the 20 s run; the
    // filter starts at the robot's true pose.
    let mut robot = Robot {
        w: 0.05,
        ..Robot::new()
    };
    let dir = tempfile::tempdir().unwrap();
    let config = dir.path().join("robot.toml");
    std::fs::write(&config, "[initial]\nx = 2.0\ny = 2.0\ntheta = 0.3\n").unwrap();
    // (ns since the epoch when the step was handed over, x, y)
    let mut truth: Vec<(u64, f64, f64)> = Vec::new();
    let mut outage_end_ns = 0;
    let (run, status) = drive_live_with(
        RangeUnit::Millimetres,
        200,
        "-TERM",
        &["--config", config.to_str().unwrap()],
        |k, e| {
            if k > 0 {
                robot.step(0.1);
            }
            e.sample(robot.sample(k % 2 == 0));
            truth.push((epoch_ns(), robot.x, robot.y));
            if k == 30 {
                for device in [Device::Laser, Device::Base] {
                    e.fault(device, Fault::Silence(Duration::from_secs(6)));
                }
                outage_end_ns = epoch_ns() + 6_000_000_000;
            }
        },
    );
    assert!(status.success(), "{}", run.stderr);
    // The devices are back when both have delivered again after the outage.
    let first_after = |topic: &str| {
        BagReader::open(&run.recording)
            .unwrap()
            .messages()
            .unwrap()
            .map(Result::unwrap)
            .filter(|m| m.topic() == topic && m.log_time > outage_end_ns)
            .map(|m| m.log_time)
            .min()
            .unwrap_or_else(|| panic!("no {topic} after the outage"))
    };
    let back_ns = first_after("/scan").max(first_after("/joint_states"));
    let truth_at = |t: u64| {
        let i = truth
            .partition_point(|s| s.0 <= t)
            .clamp(1, truth.len() - 1);
        let (a, b) = (truth[i - 1], truth[i]);
        let f = ((t as f64 - a.0 as f64) / (b.0 - a.0).max(1) as f64).clamp(0.0, 1.0);
        (a.1 + f * (b.1 - a.1), a.2 + f * (b.2 - a.2))
    };
    let poses: Vec<ekf_cli::ros2::geometry_msgs::PoseWithCovarianceStamped> =
        run.messages("/ekf/pose");
    let errors: Vec<(f64, f64)> = poses
        .iter()
        .map(|p| {
            let t = p.header.stamp.to_nanos().unwrap();
            let (x, y) = truth_at(t);
            let e = ((p.pose.pose.position.x - x).powi(2) + (p.pose.pose.position.y - y).powi(2))
                .sqrt();
            ((t as f64 - back_ns as f64) * 1e-9, e)
        })
        .collect();
    let worst = |from: f64, to: f64| {
        errors
            .iter()
            .filter(|(t, _)| (from..to).contains(t))
            .map(|(_, e)| *e)
            .fold(0.0, f64::max)
    };
    let (before, after) = (worst(-1e9, -6.5), worst(5.0, 1e9));
    eprintln!(
        "6 s outage: worst position error {before:.3} m before it, {:.3} m in the 5 s after \
         the devices were back, {after:.3} m from then on",
        worst(0.0, 5.0)
    );
    let summary = run.summary();
    assert_eq!(summary["base_outages_bridged"], 1, "{summary}");
    assert_eq!(summary["base_restarts"], 0, "{summary}");
    assert!(
        errors.iter().filter(|(t, _)| *t > 5.0).count() > 20,
        "{errors:?}"
    );
    assert!(
        after < 0.05,
        "position error {after:.3} m more than 5 s after the outage"
    );
}
