//! `ekf emulate`: the simulated robot (a scenario of `ekf simulate`, steering by the
//! truth) driven in real time and served through the three device emulators on
//! pseudo-terminals, for `ekf live` to run against; optionally the run's ground truth
//! written as an MCAP that `ekf evaluate` compares a live recording with.
//!
//! The robot stands at its start until a host has brought the laser and the base
//! controller into operation (continuous output on, a first poll answered), then drives
//! for the scenario's duration, one simulator step per period.

use super::simulate::{load_scenario, SimulateError, SimulateOptions};
use crate::config::{Config, ConfigError};
use crate::devices::sick::RangeUnit;
use crate::emulate::robot::robot_sample;
use crate::emulate::{Device, EmulatorOptions, Emulators, GpsReport};
use crate::geo::GeoOrigin;
use crate::mcap_io::{BagWriter, WriteError};
use crate::ros2::build::{odometry, MAP_FRAME};
use crate::sim::{Sample, Scenario, Simulator};
use ekf_core::{angle_diff, wrap_angle, Pose2};
use lrf_lines::MatchParams;
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

/// Topic of the true pose in the `--truth` MCAP.
pub const TRUTH_TOPIC: &str = "/ground_truth";
/// Time between true poses in the `--truth` MCAP: finer than the simulator's step (the
/// true pose interpolated in between), so a live estimate stamped at any instant has a
/// true pose within 5 ms (`ekf evaluate` pairs poses up to 10 ms apart).
pub const TRUTH_PERIOD: Duration = Duration::from_millis(10);
/// Name of the configuration `ekf live` should use, in the devices' folder.
pub const CONFIG_FILE: &str = "live.toml";

/// How `ekf emulate` runs.
#[derive(Debug, Clone, Default)]
pub struct EmulateOptions {
    /// A built-in scenario, or a line map (`.json`).
    pub scenario: String,
    /// The simulator's settings (seed, duration; steering is always by the truth).
    pub simulate: SimulateOptions,
    /// Write the true poses to this MCAP.
    pub truth: Option<PathBuf>,
    /// Folder of the device links and the configuration (which stays there, for `ekf
    /// replay` of a live recording); `None`: a new one under the system's temporary
    /// folder, removed at the end.
    pub dir: Option<PathBuf>,
    /// Where the room lies on the globe; `None`: the GPS has no fix (indoors).
    pub gps_origin: Option<GeoOrigin>,
}

/// Why an emulation failed.
#[derive(Debug, thiserror::Error)]
pub enum EmulateError {
    /// The scenario or an option is not usable.
    #[error(transparent)]
    Scenario(#[from] SimulateError),
    /// The preset configuration failed to load (a build defect).
    #[error(transparent)]
    Config(#[from] ConfigError),
    /// The folder, a pseudo-terminal or the configuration could not be made.
    #[error("{path}: {source}")]
    Io {
        /// What was being made.
        path: String,
        /// What the OS said.
        source: std::io::Error,
    },
    /// The configuration could not be written as TOML.
    #[error("{path}: {message}")]
    Toml {
        /// The file.
        path: String,
        /// The serializer's message.
        message: String,
    },
    /// The truth MCAP could not be written.
    #[error(transparent)]
    Write(#[from] WriteError),
}

/// What `ekf emulate` reports at the end.
#[derive(Debug, Clone, Serialize)]
pub struct EmulateSummary {
    /// The scenario.
    pub scenario: String,
    /// The seed.
    pub seed: u64,
    /// Simulator steps served while driving.
    pub steps: u64,
    /// Laser sweeps served while driving.
    pub scans: u64,
    /// Distance driven (m).
    pub distance_m: f64,
    /// Whether SIGINT/SIGTERM ended the run before its duration.
    pub interrupted: bool,
    /// True poses written to the truth MCAP.
    pub truth_poses: u64,
    /// The truth MCAP, if any.
    pub truth: Option<String>,
}

/// The summary as `ekf emulate` prints it at the end: one line.
impl std::fmt::Display for EmulateSummary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} (seed {}): {} steps, {} scans, {:.1} m driven",
            self.scenario, self.seed, self.steps, self.scans, self.distance_m
        )?;
        if self.interrupted {
            write!(f, ", interrupted")?;
        }
        if let Some(t) = &self.truth {
            write!(f, ", {} true poses in {t}", self.truth_poses)?;
        }
        writeln!(f)
    }
}

/// Where a started emulation's devices and configuration are: what `ekf emulate` prints
/// for `ekf live` to be pointed at.
#[derive(Debug, Clone, PartialEq)]
pub struct Connection {
    /// The laser's link.
    pub laser: PathBuf,
    /// The base controller's link.
    pub base: PathBuf,
    /// The GPS's link.
    pub gps: PathBuf,
    /// The configuration written for `ekf live`.
    pub config: PathBuf,
}

/// One line per device and the configuration, then the `ekf live` command line.
impl std::fmt::Display for Connection {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let (laser, base, gps, config) = (
            self.laser.display(),
            self.base.display(),
            self.gps.display(),
            self.config.display(),
        );
        writeln!(f, "laser: {laser}")?;
        writeln!(f, "base: {base}")?;
        writeln!(f, "gps: {gps}")?;
        writeln!(f, "config: {config}")?;
        writeln!(
            f,
            "run: ekf live --laser {laser} --base {base} --gps {gps} --config {config}"
        )
    }
}

/// The emulators set up and waiting to be run.
pub struct Emulation {
    scenario: Scenario,
    seed: u64,
    emulators: Emulators,
    dir: PathBuf,
    own_dir: bool,
    config: PathBuf,
    truth: Option<(PathBuf, BagWriter)>,
    gps_origin: Option<GeoOrigin>,
}

fn io_error(path: &Path) -> impl FnOnce(std::io::Error) -> EmulateError + '_ {
    move |source| EmulateError::Io {
        path: path.display().to_string(),
        source,
    }
}

/// The configuration `ekf live` needs for `scenario`'s robot: the paper-robot preset
/// with the scenario's geometry, encoders, laser and compass, and its start as the
/// initial pose (so the estimate is in the room's frame, as the truth is).
pub fn live_config(scenario: &Scenario) -> Result<Config, ConfigError> {
    let mut c = Config::preset("paper-robot")?;
    let (robot, laser) = (&scenario.robot, &scenario.laser);
    c.initial.x = scenario.start.x;
    c.initial.y = scenario.start.y;
    c.initial.theta = scenario.start.theta;
    c.localizer.robot.wheel_radius = robot.wheel_radius;
    c.localizer.robot.track = robot.track;
    c.localizer.wheel_noise.delta = robot.delta;
    c.localizer.laser_mount = laser.mount;
    // Live, a scan is a sweep while the robot moves, stamped when it was measured and
    // fused at the pose of that instant, from serial reads that jitter: errors that the
    // simulation's instant scans do not have. Keep the default map noise for them.
    c.localizer.matching.map_sigma_r = MatchParams::default().map_sigma_r;
    c.localizer.matching.map_sigma_psi = MatchParams::default().map_sigma_psi;
    c.localizer.extraction.range_sigma = laser.range_sigma;
    c.localizer.extraction.bearing_sigma = laser.bearing_sigma;
    // The register holds tenths of a degree: rounding adds (0.1°)²/12 to the noise.
    c.localizer.compass.variance =
        scenario.compass.sigma.powi(2) + 0.1f64.to_radians().powi(2) / 12.0;
    c.devices.ticks_per_revolution = f64::from(robot.ticks_per_rev);
    c.devices.laser_resolution_deg = laser.resolution.to_degrees();
    c.devices.laser_angle_deg = laser.fov.to_degrees().round() as u16;
    Ok(c)
}

impl Emulation {
    /// Loads the scenario, starts the emulators, writes the configuration for `ekf
    /// live` and creates the truth MCAP.
    pub fn start(options: &EmulateOptions) -> Result<Self, EmulateError> {
        let scenario = load_scenario(&options.scenario, &options.simulate)?;
        let config = live_config(&scenario)?;
        let (dir, own_dir) = match &options.dir {
            Some(d) => (d.clone(), false),
            None => (
                std::env::temp_dir().join(format!("ekf-emulate-{}", std::process::id())),
                true,
            ),
        };
        let emulators = Emulators::start(&EmulatorOptions {
            dir: dir.clone(),
            unit: RangeUnit::Millimetres,
            unit_id: config.devices.base_unit_id,
        })
        .map_err(io_error(&dir))?;
        let config_path = dir.join(CONFIG_FILE);
        let text = toml::to_string(&config).map_err(|e| EmulateError::Toml {
            path: config_path.display().to_string(),
            message: e.to_string(),
        })?;
        let header = format!(
            "# ekf live against `ekf emulate {}` (seed {}): the paper-robot preset with the\n# simulated robot's geometry, sensors and start pose.\n",
            scenario.name, options.simulate.seed
        );
        std::fs::write(&config_path, header + &text).map_err(io_error(&config_path))?;
        let truth = match &options.truth {
            Some(path) => {
                let mut w = BagWriter::create(path)?;
                w.write_metadata(
                    "emulation",
                    &[
                        ("generator", "ekf emulate".into()),
                        ("scenario", scenario.name.clone()),
                        ("seed", options.simulate.seed.to_string()),
                        (
                            "ground_truth",
                            format!(
                                "{TRUTH_TOPIC}: the simulated true pose every {} ms, stamped with the wall clock",
                                TRUTH_PERIOD.as_millis()
                            ),
                        ),
                    ],
                )?;
                Some((path.clone(), w))
            }
            None => None,
        };
        Ok(Self {
            scenario,
            seed: options.simulate.seed,
            emulators,
            dir,
            own_dir,
            config: config_path,
            truth,
            gps_origin: options.gps_origin,
        })
    }

    /// The link through which `device` is reached.
    pub fn path(&self, device: Device) -> PathBuf {
        self.emulators.path(device)
    }

    /// Where the devices and the configuration are.
    pub fn connection(&self) -> Connection {
        Connection {
            laser: self.path(Device::Laser),
            base: self.path(Device::Base),
            gps: self.path(Device::Gps),
            config: self.config.clone(),
        }
    }

    /// Holds the robot until a host is connected, then drives the scenario in real time
    /// until its end or until `stop` is set; stops the emulators (their links go) and
    /// finishes the truth MCAP.
    pub fn run(mut self, stop: &AtomicBool) -> Result<EmulateSummary, EmulateError> {
        let result = self.drive(stop);
        let Emulation {
            emulators,
            truth,
            config,
            dir,
            own_dir,
            ..
        } = self;
        emulators.stop();
        if own_dir {
            // Only if then empty: nothing but our own links and file was in it.
            let _ = std::fs::remove_file(&config);
            let _ = std::fs::remove_dir(&dir);
        }
        let mut summary = result?;
        if let Some((path, writer)) = truth {
            writer.finish()?;
            summary.truth = Some(path.display().to_string());
        }
        Ok(summary)
    }

    fn drive(&mut self, stop: &AtomicBool) -> Result<EmulateSummary, EmulateError> {
        let scenario = self.scenario.clone();
        let mut sim = Simulator::new(&scenario, self.seed);
        let dt = Duration::from_secs_f64(scenario.dt);
        let gps_every = (1.0 / scenario.dt).round().max(1.0) as u64;
        let mut summary = EmulateSummary {
            scenario: scenario.name.clone(),
            seed: self.seed,
            steps: 0,
            scans: 0,
            distance_m: 0.0,
            interrupted: false,
            truth_poses: 0,
            truth: None,
        };
        let mut now = sim.measure();

        // Standing at the start: step 0 served every period until a host is connected.
        let mut due = Instant::now();
        let mut k = 0u64;
        while !(self.emulators.ready(Device::Laser) && self.emulators.ready(Device::Base)) {
            let held = Sample {
                scan: now
                    .scan
                    .clone()
                    .filter(|_| k.is_multiple_of(u64::from(scenario.laser.period_steps.max(1)))),
                ..now.clone()
            };
            let gps = k.is_multiple_of(gps_every).then(|| self.gps(&now.truth));
            self.emulators.sample(robot_sample(
                &scenario.laser,
                &held,
                None,
                due,
                dt,
                epoch_ns(),
                gps,
            ));
            k += 1;
            due += dt;
            if !sleep_until(due, stop) {
                summary.interrupted = true;
                return Ok(summary);
            }
        }

        // Driving: step k is served at t0 + k·dt, the next one computed ahead so the
        // encoders move on towards it between steps.
        let (t0, epoch0) = (Instant::now(), epoch_ns());
        let steps = scenario.steps();
        for k in 0..=steps {
            let next = (k < steps).then(|| {
                summary.distance_m += sim.advance(&sim.pose());
                sim.measure()
            });
            let at = t0 + dt * k as u32;
            let t_ns = epoch0 + dt.as_nanos() as u64 * k;
            let gps = k.is_multiple_of(gps_every).then(|| self.gps(&now.truth));
            self.emulators.sample(robot_sample(
                &scenario.laser,
                &now,
                next.as_ref(),
                at,
                dt,
                t_ns,
                gps,
            ));
            summary.steps = k;
            summary.scans += u64::from(now.scan.is_some());
            self.write_truth(&now, next.as_ref(), t_ns, dt, &mut summary)?;
            if !sleep_until(at + dt, stop) {
                summary.interrupted = true;
                break;
            }
            match next {
                Some(n) => now = n,
                None => break,
            }
        }
        Ok(summary)
    }

    fn gps(&self, truth: &Pose2<f64>) -> GpsReport {
        match &self.gps_origin {
            Some(o) => GpsReport::Fix(o.fix_at(truth.x, truth.y)),
            None => GpsReport::NoFix,
        }
    }

    /// The true pose from step `now` (stamped `t_ns`) up to the next step, every
    /// [`TRUTH_PERIOD`], interpolated in between.
    fn write_truth(
        &mut self,
        now: &Sample,
        next: Option<&Sample>,
        t_ns: u64,
        dt: Duration,
        summary: &mut EmulateSummary,
    ) -> Result<(), EmulateError> {
        let Some((_, writer)) = self.truth.as_mut() else {
            return Ok(());
        };
        let (a, period) = (now.truth, TRUTH_PERIOD.as_nanos() as u64);
        let count = match next {
            Some(_) => (dt.as_nanos() as u64).div_ceil(period),
            None => 1,
        };
        for j in 0..count {
            let t = t_ns + j * period;
            let pose = match next {
                Some(n) => {
                    let f = (j * period) as f64 / dt.as_nanos() as f64;
                    let b = n.truth;
                    Pose2::new(
                        a.x + f * (b.x - a.x),
                        a.y + f * (b.y - a.y),
                        wrap_angle(a.theta + f * angle_diff(b.theta, a.theta)),
                    )
                }
                None => a,
            };
            writer.write(TRUTH_TOPIC, &odometry(t, &pose, MAP_FRAME))?;
            summary.truth_poses += 1;
        }
        Ok(())
    }
}

/// Nanoseconds since the Unix epoch now.
fn epoch_ns() -> u64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| d.as_nanos() as u64)
}

/// Sleeps until `due`, waking every 50 ms to look at `stop`; `false` if it was set.
fn sleep_until(due: Instant, stop: &AtomicBool) -> bool {
    loop {
        if stop.load(Ordering::Relaxed) {
            return false;
        }
        let left = due.saturating_duration_since(Instant::now());
        if left.is_zero() {
            return true;
        }
        std::thread::sleep(left.min(Duration::from_millis(50)));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_live_configuration_describes_the_simulated_robot() {
        let s = load_scenario("paper", &SimulateOptions::default()).unwrap();
        let c = live_config(&s).unwrap();
        assert_eq!((c.initial.x, c.initial.y, c.initial.theta), (2.0, 1.0, 0.0));
        assert_eq!(c.devices.ticks_per_revolution, 2000.0);
        assert_eq!(c.localizer.laser_mount, s.laser.mount);
        // It round-trips through the TOML that ekf live reads.
        let text = toml::to_string(&c).unwrap();
        assert_eq!(Config::from_toml(&text, "live.toml").unwrap(), c);
        let sigma = c.localizer.compass.variance.sqrt().to_degrees();
        assert!(sigma > 0.1 && sigma < 0.11, "{sigma}");
    }

    #[test]
    fn summary_and_connection_as_printed() {
        let mut summary = EmulateSummary {
            scenario: "paper".into(),
            seed: 3,
            steps: 120,
            scans: 60,
            distance_m: 4.26,
            interrupted: false,
            truth_poses: 0,
            truth: None,
        };
        assert_eq!(
            summary.to_string(),
            "paper (seed 3): 120 steps, 60 scans, 4.3 m driven\n"
        );
        summary.interrupted = true;
        summary.truth = Some("t.mcap".into());
        summary.truth_poses = 99;
        assert_eq!(
            summary.to_string(),
            "paper (seed 3): 120 steps, 60 scans, 4.3 m driven, interrupted, 99 true poses in \
             t.mcap\n"
        );
        let c = Connection {
            laser: "/d/laser".into(),
            base: "/d/base".into(),
            gps: "/d/gps".into(),
            config: "/d/live.toml".into(),
        };
        assert_eq!(
            c.to_string(),
            "laser: /d/laser\nbase: /d/base\ngps: /d/gps\nconfig: /d/live.toml\nrun: ekf live \
             --laser /d/laser --base /d/base --gps /d/gps --config /d/live.toml\n"
        );
    }
}
