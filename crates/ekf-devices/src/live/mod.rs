//! `ekf live`: the filter on the robot's serial devices. Readings become the ROS 2
//! messages of docs/ARCHITECTURE.md §4, are recorded (with `/tf_static` for the laser mount and the
//! estimates) and fed to the same filter loop as `ekf replay`, so a replay of the
//! recording gives the same poses bit for bit. Devices that fail are reported and
//! reconnected with backoff; a device silent at start-up is an error naming its port.

pub mod messages;
mod workers;

use crate::devices::modbus_base::{BaseConfig, BaseReading, EncoderTracker, WheelTicks};
use crate::devices::sick::{BaudRate, SickConfig, Variant};
use crate::devices::DeviceError;
use ekf_core::Pose2;
use ekf_fusion::Forecast;
use ekf_ros::config::{Config, MotionSource};
use ekf_ros::mcap_io::WriteError;
use ekf_ros::replay::{Mode, Preamble, ReplayError, ReplayOptions, ReplaySummary, Run};
use ekf_ros::ros2::builtin_interfaces::Time;
use ekf_ros::ros2::diagnostic_msgs::{DiagnosticArray, DiagnosticStatus, KeyValue};
use ekf_ros::ros2::std_msgs::Header;
use ekf_ros::ros2::AnyMessage;
use messages::Recorder;
use nalgebra::Matrix3;
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, RecvTimeoutError};
use std::sync::Arc;
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};
use workers::{Data, DeviceCounters, Reading};

/// Log time a chunk of the recording spans before it is closed and synced to the disk:
/// what a hard kill or a power cut can lose at most (the recording then has no summary,
/// and `ekf replay` rebuilds its index from the chunks).
pub const RECORDING_CHUNK_NS: u64 = 1_000_000_000;

/// Topic of the device diagnostics in a recording.
pub const DEVICE_DIAGNOSTICS_TOPIC: &str = "/diagnostics";
/// Topic of the GPS fixes in a recording.
pub const FIX_TOPIC: &str = "/fix";

/// What to run on and where to write.
#[derive(Debug, Clone)]
pub struct LiveOptions {
    /// The laser's port.
    pub laser: String,
    /// The base controller's port.
    pub base: String,
    /// The GPS's port, if there is one.
    pub gps: Option<String>,
    /// Record the raw readings and the estimates to this MCAP.
    pub record: Option<PathBuf>,
    /// A line map (JSON); `None`: built from the first scan.
    pub map: Option<PathBuf>,
    /// Which sensors the filter uses.
    pub mode: Mode,
}

/// What the run reports as it goes.
#[derive(Debug, Clone, PartialEq)]
pub enum LiveEvent {
    /// The estimate now, reported as wheel readings arrive (at most one per reading, each
    /// later than the one before, none until a first motion step has been fused): the
    /// fused state predicted through the wheel readings still held back (measurements
    /// made before them may still be arriving; see [`run`]), as robot_localization's
    /// `predict_to_current_time` does. The recording keeps the fused estimates.
    Pose {
        /// Time (ns since the Unix epoch): when the newest wheel reading held back was
        /// made, or the fused state's time if none is.
        t_ns: u64,
        /// Time of the fused state it was predicted from (ns since the Unix epoch).
        fused_ns: u64,
        /// The pose.
        pose: Pose2<f64>,
        /// Its covariance.
        covariance: Matrix3<f64>,
    },
    /// A device connected, failed or came back; or (`filter`) a pose could not be
    /// predicted ahead.
    Device {
        /// `laser`, `base`, `gps` or `filter`.
        device: &'static str,
        /// 0 OK, 1 warning.
        level: u8,
        /// What happened.
        text: String,
    },
}

impl LiveEvent {
    /// A pose as one JSON object (`ekf live --json` prints one per line): `t_ns`,
    /// `fused_ns`, `x`, `y`, `theta`, `sigma_xy` (`[σx, σy]`) and `sigma_theta`. `None`
    /// for a device event.
    pub fn pose_json(&self) -> Option<serde_json::Value> {
        match self {
            LiveEvent::Pose {
                t_ns,
                fused_ns,
                pose,
                covariance,
            } => Some(serde_json::json!({
                "t_ns": t_ns, "fused_ns": fused_ns,
                "x": pose.x, "y": pose.y, "theta": pose.theta,
                "sigma_xy": [covariance[(0, 0)].sqrt(), covariance[(1, 1)].sqrt()],
                "sigma_theta": covariance[(2, 2)].sqrt(),
            })),
            LiveEvent::Device { .. } => None,
        }
    }
}

/// One line as `ekf live` prints it: a pose with its time (s), position, heading, the
/// position's σ (√(σx² + σy²)) and how long it has been predicted on odometry alone; or
/// a device's message, prefixed `warning: ` when it is one.
impl std::fmt::Display for LiveEvent {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            LiveEvent::Pose {
                t_ns,
                fused_ns,
                pose,
                covariance,
            } => write!(
                f,
                "{:.3}  x {:8.3} m  y {:8.3} m  θ {:7.2}°  σxy {:.3} m  (odometry since {:.2} s)",
                *t_ns as f64 * 1e-9,
                pose.x,
                pose.y,
                pose.theta.to_degrees(),
                (covariance[(0, 0)] + covariance[(1, 1)]).sqrt(),
                t_ns.saturating_sub(*fused_ns) as f64 * 1e-9
            ),
            LiveEvent::Device { level, text, .. } => {
                let what = if *level == 0 { "" } else { "warning: " };
                write!(f, "{what}{text}")
            }
        }
    }
}

/// Counts of everything that happened, per device and in the filter.
#[derive(Debug, Clone, serde::Serialize)]
pub struct LiveSummary {
    /// The filter's summary (as `ekf replay` reports it for the recording).
    pub filter: ReplaySummary,
    /// Each device's counters since its last (re)connection.
    pub devices: BTreeMap<&'static str, serde_json::Value>,
    /// Reconnections per device.
    pub reconnects: BTreeMap<&'static str, u64>,
    /// Base reads that repeated the previous sample.
    pub base_repeated_samples: u64,
    /// Base samples whose replies were lost (counter jumps).
    pub base_missed_samples: u64,
    /// Base reads refused: an encoder change no wheel can make in the time, or a
    /// sample counter that stepped back (the controller restarted its counts).
    pub base_implausible_samples: u64,
    /// Base reconnections after which the controller had counted on: the wheel motion
    /// of the outage was kept (fused as one step, its noise growing with the distance).
    pub base_outages_bridged: u64,
    /// Base reconnections to a restarted controller: the motion of the outage is lost.
    pub base_restarts: u64,
    /// Compass bearings out of range (not fused).
    pub compass_invalid: u64,
    /// GPS fixes recorded.
    pub gps_fixes: u64,
    /// Measurements that arrived after a later one had been fused: dropped.
    pub late_readings: u64,
    /// The recording, if any.
    pub recording: Option<String>,
}

/// The summary as `ekf live` prints it at the end: the filter's counts, each device's
/// counters and reconnections, and the recording.
impl std::fmt::Display for LiveSummary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let s = &self.filter;
        writeln!(
            f,
            "live: motion steps {}, scans {} (used {}), lines fused {}, compass fused {}",
            s.motion_steps, s.lines.scans, s.lines.scans_used, s.lines.fused, s.compass.accepted
        )?;
        for (device, counters) in &self.devices {
            writeln!(f, "  {device}: {counters}")?;
        }
        for (device, n) in &self.reconnects {
            writeln!(f, "  {device}: reconnected {n} times")?;
        }
        if self.base_outages_bridged + self.base_restarts > 0 {
            writeln!(
                f,
                "  base after reconnecting: the motion of the outage kept {} times, the \
                 controller restarted {} times",
                self.base_outages_bridged, self.base_restarts
            )?;
        }
        if let Some(r) = &self.recording {
            writeln!(f, "  recording: {r}")?;
        }
        Ok(())
    }
}

/// Why a live run failed.
#[derive(Debug, thiserror::Error)]
pub enum LiveError {
    /// A device could not be brought up.
    #[error(transparent)]
    Device(#[from] DeviceError),
    /// The configuration does not suit live mode.
    #[error("{0}")]
    Config(String),
    /// The filter or its outputs failed.
    #[error(transparent)]
    Filter(#[from] ReplayError),
    /// A message could not be recorded.
    #[error(transparent)]
    Record(#[from] WriteError),
}

/// The result of a run: the summary, and the error that ended it early, if any (the
/// recording is finished either way).
#[derive(Debug)]
pub struct LiveOutcome {
    /// Counts.
    pub summary: LiveSummary,
    /// Why the run ended early.
    pub failure: Option<LiveError>,
}

/// How much longer than a device's announced latency a measurement is held before the
/// measurements made up to then are fused: covers a worker thread descheduled between
/// stamping a measurement and handing it over.
const HOLD_SLACK: Duration = Duration::from_millis(100);

/// Nanoseconds since the Unix epoch for monotonic instants.
struct Clock {
    epoch_ns: u64,
    started: Instant,
    last: u64,
}

impl Clock {
    fn new() -> Self {
        let epoch_ns = SystemTime::now()
            .duration_since(UNIX_EPOCH)
            .map_or(0, |d| d.as_nanos() as u64);
        Self {
            epoch_ns,
            started: Instant::now(),
            last: 0,
        }
    }

    /// The stamp of `t` (instants before the clock started get its start).
    fn stamp(&self, t: Instant) -> u64 {
        self.epoch_ns + t.saturating_duration_since(self.started).as_nanos() as u64
    }

    /// The stamp of now, strictly increasing per call (diagnostics).
    fn now(&mut self) -> u64 {
        self.last = self.stamp(Instant::now()).max(self.last + 1);
        self.last
    }
}

/// The laser variant the configuration asks for.
fn variant(config: &Config) -> Result<Variant, LiveError> {
    let d = &config.devices;
    let v = Variant {
        angle_deg: d.laser_angle_deg,
        resolution_cdeg: (d.laser_resolution_deg * 100.0).round() as u16,
    };
    if v.is_supported() {
        Ok(v)
    } else {
        Err(LiveError::Config(format!(
            "devices.laser_angle_deg = {} with devices.laser_resolution_deg = {}: an LMS 2xx scans 180° at 1° or 0.5°, or 100° at 1°, 0.5° or 0.25°",
            d.laser_angle_deg, d.laser_resolution_deg
        )))
    }
}

/// Runs until `stop` is set (SIGINT/SIGTERM) or a device fails at start-up; `on_event`
/// receives poses and device news.
///
/// Readings are fused in the order they were made, once none made before them can still
/// arrive: the laser's stamp is the middle of its sweep, a few hundred milliseconds
/// before its telegram is through the serial line. The poses reported are not that late:
/// as wheel readings arrive, the fused state is predicted ahead through the wheel
/// readings held back ([`LiveEvent::Pose`]).
pub fn run(
    config: &Config,
    options: &LiveOptions,
    stop: Arc<AtomicBool>,
    on_event: &mut dyn FnMut(LiveEvent),
) -> Result<LiveOutcome, LiveError> {
    let started = Instant::now();
    if config.motion.source == MotionSource::Odom {
        return Err(LiveError::Config(
            "motion.source = \"odom\": live mode drives the filter from the wheel encoders; use \"auto\" or \"joint_states\"".into(),
        ));
    }
    let d = &config.devices;
    let variant = variant(config)?;
    let laser_baud = BaudRate::from_bits_per_second(d.laser_baud)
        .filter(|b| matches!(b, BaudRate::B38400 | BaudRate::B500000))
        .ok_or_else(|| {
            LiveError::Config(format!(
                "devices.laser_baud = {}: expected 38400 or 500000",
                d.laser_baud
            ))
        })?;
    d.validate()
        .map_err(|e| LiveError::Config(e.in_table("devices").to_string()))?;
    let timeout = Duration::from_secs_f64(d.timeout_s);
    // Before the workers: every measurement is made after the recording's start.
    let clock = Clock::new();

    // The devices connect while the recording starts; a device silent at start-up ends
    // the run (the recording then holds only its start).
    let (tx, rx) = mpsc::channel();
    let worker_stop = Arc::new(AtomicBool::new(false));
    let mut threads = vec![
        workers::spawn::<workers::Laser>(
            options.laser.clone(),
            SickConfig {
                baud: laser_baud,
                variant,
                scan_timeout: timeout,
                ..SickConfig::default()
            },
            tx.clone(),
            Arc::clone(&worker_stop),
        ),
        workers::spawn::<workers::Base>(
            options.base.clone(),
            workers::BaseSettings {
                client: BaseConfig {
                    unit_id: d.base_unit_id,
                    silence_timeout: timeout,
                    ..BaseConfig::default()
                },
                baud: d.base_baud,
                period: Duration::from_secs_f64(1.0 / d.poll_rate_hz),
            },
            tx.clone(),
            Arc::clone(&worker_stop),
        ),
    ];
    if let Some(gps) = &options.gps {
        threads.push(workers::spawn::<workers::Gps>(
            gps.clone(),
            workers::GpsSettings {
                baud: d.gps_baud,
                timeout,
            },
            tx.clone(),
            Arc::clone(&worker_stop),
        ));
    }
    drop(tx);
    let shutdown = |threads: Vec<std::thread::JoinHandle<()>>| {
        worker_stop.store(true, Ordering::Relaxed);
        for t in threads {
            let _ = t.join();
        }
    };

    let mut live = match Live::new(config, options, variant, clock) {
        Ok(live) => live,
        Err(e) => {
            // The laser must not be left streaming.
            shutdown(threads);
            return Err(e);
        }
    };
    // Devices that have connected once: a further OK from one is a reconnection.
    let mut connected: BTreeSet<&'static str> = BTreeSet::new();
    let mut failure = None;
    let mut last_diagnostics = Instant::now();
    // Until the laser says at which rate it runs: the configured one.
    let mut latency: BTreeMap<&'static str, Duration> = BTreeMap::from([(
        "laser",
        laser_baud.transmission_time(variant.telegram_bytes()) + variant.sweep_duration() / 2,
    )]);
    live.hold = latency.values().max().copied().unwrap_or_default() + HOLD_SLACK;
    while !stop.load(Ordering::Relaxed) {
        let first = match rx.recv_timeout(Duration::from_millis(50)) {
            Ok(r) => Some(r),
            Err(RecvTimeoutError::Timeout) => None,
            Err(RecvTimeoutError::Disconnected) => break,
        };
        let mut step = Ok(());
        let mut wheels_moved = false;
        // Everything that is waiting; then the channel is empty.
        for reading in first
            .into_iter()
            .chain(std::iter::from_fn(|| rx.try_recv().ok()))
        {
            step = match reading {
                Reading::Failed(e) => {
                    // Only a start-up failure gets here (later ones are retried); the
                    // recording is finished when `live` is dropped.
                    shutdown(threads);
                    return Err(e.into());
                }
                Reading::Status {
                    device,
                    level,
                    text,
                    latency: l,
                } => {
                    if level == workers::OK {
                        if !connected.insert(device) {
                            *live.summary.reconnects.entry(device).or_default() += 1;
                        }
                        latency.insert(device, l);
                        live.hold =
                            latency.values().max().copied().unwrap_or_default() + HOLD_SLACK;
                    }
                    on_event(LiveEvent::Device {
                        device,
                        level,
                        text: text.clone(),
                    });
                    live.device_status(device, level, &text)
                }
                Reading::Counters(c) => {
                    live.counters(c);
                    Ok(())
                }
                Reading::Data { at, data } => {
                    let wheels = matches!(data, Data::Base { .. });
                    wheels_moved |= live.hold_back(at, data) && wheels;
                    Ok(())
                }
            };
            if step.is_err() {
                break;
            }
        }
        // A measurement not yet handed over is made after `drained` less the
        // latency of its device: what was made before that can be fused, in order.
        let drained = Instant::now();
        if step.is_ok() {
            if let Some(until) = drained.checked_sub(live.hold) {
                step = live.release(Some(until));
            }
        }
        if step.is_ok() && wheels_moved {
            live.report_pose(on_event);
        }
        if let Err(e) = step {
            failure = Some(e);
            break;
        }
        if last_diagnostics.elapsed() >= Duration::from_secs(1) {
            last_diagnostics = Instant::now();
            if let Err(e) = live.counters_diagnostics() {
                failure = Some(e);
                break;
            }
        }
    }
    shutdown(threads);
    // What was still held back.
    match live.release(None) {
        Ok(()) => live.report_pose(on_event),
        Err(e) => {
            failure.get_or_insert(e);
        }
    }
    let _ = live.counters_diagnostics();
    live.finish(started, failure)
}

/// The wheel positions from the base controller's reads, across reconnections.
#[derive(Debug, Clone)]
struct BaseTicks {
    tracker: EncoderTracker,
    /// The base worker's connection the tracker follows.
    connection: u64,
}

impl BaseTicks {
    /// The wheel positions after `reading`, made at `t_ns` and received on the base
    /// worker's connection `connection` ([`EncoderTracker::update`]). After a new
    /// connection the first read tells whether the controller counted on while the line
    /// was down (the motion of the outage is kept) or restarted (a new reference).
    fn update(&mut self, reading: BaseReading, connection: u64, t_ns: u64) -> Option<WheelTicks> {
        if connection != self.connection {
            self.tracker.reconnected();
            self.connection = connection;
        }
        self.tracker.update(reading, t_ns)
    }
}

/// The main loop's state.
struct Live<'a> {
    config: &'a Config,
    run: Run<'a>,
    recorder: Recorder,
    clock: Clock,
    base: BaseTicks,
    variant: Variant,
    counters: BTreeMap<&'static str, DeviceCounters>,
    summary: LiveSummary,
    /// Measurements held back until none made before them can still arrive, in the
    /// order they were made (ties in the order they came).
    pending: BTreeMap<(Instant, u64), Data>,
    arrived: u64,
    /// How long after a measurement the ones made before it have all arrived: the
    /// largest device latency, plus [`HOLD_SLACK`].
    hold: Duration,
    /// Stamp of the last message fused (at first the recording's start).
    last_ns: u64,
    /// Time of the last pose reported (0: none yet).
    reported_ns: u64,
}

impl<'a> Live<'a> {
    fn new(
        config: &'a Config,
        options: &LiveOptions,
        variant: Variant,
        clock: Clock,
    ) -> Result<Self, LiveError> {
        let t0 = clock.stamp(clock.started);
        let tf = messages::laser_transform(config, t0);
        let preamble = Preamble {
            scan_frame: Some(config.devices.laser_frame.clone()),
            transforms: tf.transforms.clone(),
            first_reference: None,
        };
        let replay_options = ReplayOptions {
            mode: options.mode,
            map: options.map.clone(),
            init_from_truth: false,
            out_mcap: options.record.clone(),
            tum: None,
            keep_trajectories: false,
            global: false,
            grow_map: false,
        };
        let name = options
            .record
            .as_ref()
            .map_or_else(|| "live".into(), |p| p.display().to_string());
        let mut run = Run::start(
            config,
            &replay_options,
            &preamble,
            true,
            &name,
            &config.topics.joint_states,
            // The readings come in the order they were made (`hold_back`): each is fused
            // as it is handed on.
            0,
        )?;
        if let Some(out) = run.output() {
            out.writer().close_chunks_every(RECORDING_CHUNK_NS);
        }
        let mut recorder = Recorder::new(Path::new(&name));
        let at = recorder.record_at(run.output(), &config.topics.tf_static, t0, &tf)?;
        run.handle_decoded(&at.channel, at.log_time, at.log_time, tf.into())?;
        Ok(Self {
            config,
            run,
            recorder,
            clock,
            base: BaseTicks {
                tracker: EncoderTracker::new(
                    config.devices.max_wheel_turns_per_s * config.devices.ticks_per_revolution,
                ),
                connection: 0,
            },
            variant,
            counters: BTreeMap::new(),
            summary: LiveSummary {
                filter: ReplaySummary::default(),
                devices: BTreeMap::new(),
                reconnects: BTreeMap::new(),
                base_repeated_samples: 0,
                base_missed_samples: 0,
                base_implausible_samples: 0,
                base_outages_bridged: 0,
                base_restarts: 0,
                compass_invalid: 0,
                gps_fixes: 0,
                late_readings: 0,
                recording: options.record.as_ref().map(|p| p.display().to_string()),
            },
            pending: BTreeMap::new(),
            arrived: 0,
            hold: HOLD_SLACK,
            last_ns: t0,
            reported_ns: 0,
        })
    }

    fn counters(&mut self, c: DeviceCounters) {
        let name = match c {
            DeviceCounters::Laser(_) => "laser",
            DeviceCounters::Base(_) => "base",
            DeviceCounters::Gps(_) => "gps",
        };
        self.counters.insert(name, c);
    }

    /// Holds a measurement made at `at` back until those made before it have arrived;
    /// one made before a measurement already fused is late: counted and dropped (fusing
    /// or recording it out of order would make the replay differ). Returns whether it
    /// was kept.
    fn hold_back(&mut self, at: Instant, data: Data) -> bool {
        if self.clock.stamp(at) < self.last_ns {
            self.summary.late_readings += 1;
            return false;
        }
        self.pending.insert((at, self.arrived), data);
        self.arrived += 1;
        true
    }

    /// Fuses the held measurements made up to `until` (all with `None`), oldest first.
    fn release(&mut self, until: Option<Instant>) -> Result<(), LiveError> {
        while let Some(entry) = self.pending.first_entry() {
            let at = entry.key().0;
            if until.is_some_and(|u| at > u) {
                break;
            }
            let data = entry.remove();
            self.reading(at, data)?;
        }
        Ok(())
    }

    /// The stamp of a message about a measurement made at `at`: strictly after the last
    /// one (messages never share a stamp, and the recording's order is the stamps').
    fn stamp(&mut self, at: Instant) -> u64 {
        self.last_ns = self.clock.stamp(at).max(self.last_ns + 1);
        self.last_ns
    }

    /// Reports the pose now ([`forecast`](Self::forecast)) if it is later than the last
    /// one reported. A prediction that fails is reported as a warning, not as the run's
    /// failure: fusing the same readings will tell whether the filter itself failed.
    fn report_pose(&mut self, on_event: &mut dyn FnMut(LiveEvent)) {
        match self.forecast() {
            Ok(Some(f)) if f.t_ns > self.reported_ns => {
                self.reported_ns = f.t_ns;
                on_event(LiveEvent::Pose {
                    t_ns: f.t_ns,
                    fused_ns: f.fused_ns,
                    pose: f.pose,
                    covariance: f.covariance,
                });
            }
            Ok(_) => {}
            Err(e) => on_event(LiveEvent::Device {
                device: "filter",
                level: 1,
                text: format!("the pose could not be predicted ahead: {e}"),
            }),
        }
    }

    /// The pose now: the fused state predicted through the wheel readings held back
    /// ([`Run::forecast`]), each turned into the joint state fusing it will record (but
    /// for the nanosecond its stamp may be moved by to keep stamps apart).
    fn forecast(&self) -> Result<Option<Forecast>, LiveError> {
        let mut base = self.base.clone();
        let joint_states: Vec<_> = self
            .pending
            .iter()
            .filter_map(|(&(at, _), data)| {
                let Data::Base {
                    reading,
                    connection,
                } = data
                else {
                    return None;
                };
                let t = self.clock.stamp(at);
                let ticks = base.update(*reading, *connection, t)?;
                Some(messages::joint_state(self.config, t, ticks))
            })
            .collect();
        Ok(self.run.forecast(&joint_states)?)
    }

    fn reading(&mut self, at: Instant, data: Data) -> Result<(), LiveError> {
        let topics = &self.config.topics;
        match data {
            Data::Scan { ranges, unit } => {
                let t = self.stamp(at);
                let scan = messages::laser_scan(self.config, self.variant, unit, t, ranges);
                self.feed(&topics.scan.clone(), scan)?;
            }
            Data::Base {
                reading: r,
                connection,
            } => {
                let Some(ticks) = self.base.update(r, connection, self.clock.stamp(at)) else {
                    return Ok(());
                };
                let t = self.stamp(at);
                let joints = messages::joint_state(self.config, t, ticks);
                self.feed(&topics.joint_states.clone(), joints)?;
                match r.bearing() {
                    Some(bearing) => {
                        let t = self.stamp(at);
                        let field = messages::compass(self.config, t, bearing);
                        self.feed(&topics.compass.clone(), field)?;
                    }
                    None => self.summary.compass_invalid += 1,
                }
            }
            Data::Fix(f) => {
                let t = self.stamp(at);
                let fix = f.to_nav_sat_fix(t, &self.config.devices.gps_frame);
                self.summary.gps_fixes += 1;
                self.feed(FIX_TOPIC, fix)?;
            }
        }
        Ok(())
    }

    /// Records a message and runs the filter on it as it is (no encoding unless it is
    /// recorded, no decoding): its stamp is its log time, so replaying the recording
    /// fuses it at the same time.
    fn feed<M>(&mut self, topic: &str, message: M) -> Result<(), LiveError>
    where
        M: ekf_ros::ros2::RosMessage + ekf_ros::ros2::Stamped + Into<AnyMessage>,
    {
        let at = self.recorder.record(self.run.output(), topic, &message)?;
        self.run
            .handle_decoded(&at.channel, at.log_time, at.log_time, message.into())?;
        Ok(())
    }

    fn device_status(&mut self, device: &str, level: u8, text: &str) -> Result<(), LiveError> {
        self.diagnostics(vec![status(device, level, text, Vec::new())])
    }

    /// The encoder tracker's counts, into the summary.
    fn copy_base_counts(&mut self) {
        let t = &self.base.tracker;
        let s = &mut self.summary;
        s.base_repeated_samples = t.repeated;
        s.base_missed_samples = t.missed;
        s.base_implausible_samples = t.implausible;
        s.base_outages_bridged = t.outages_bridged;
        s.base_restarts = t.restarts;
    }

    /// Every device's counters as one diagnostics message.
    fn counters_diagnostics(&mut self) -> Result<(), LiveError> {
        self.copy_base_counts();
        let statuses = self
            .counters
            .iter()
            .map(|(name, c)| {
                let values = match serde_json::to_value(c) {
                    Ok(serde_json::Value::Object(map)) => map
                        .into_iter()
                        .map(|(k, v)| KeyValue {
                            key: k,
                            value: v.to_string(),
                        })
                        .collect(),
                    _ => Vec::new(),
                };
                status(
                    name,
                    workers::OK,
                    "counters since the last connection",
                    values,
                )
            })
            .collect();
        self.diagnostics(statuses)
    }

    fn diagnostics(&mut self, statuses: Vec<DiagnosticStatus>) -> Result<(), LiveError> {
        let t = self.clock.now();
        let msg = DiagnosticArray {
            header: Header {
                stamp: Time::from_nanos(t).unwrap_or_default(),
                frame_id: String::new(),
            },
            status: statuses,
        };
        self.recorder
            .record(self.run.output(), DEVICE_DIAGNOSTICS_TOPIC, &msg)?;
        Ok(())
    }

    fn finish(
        mut self,
        started: Instant,
        failure: Option<LiveError>,
    ) -> Result<LiveOutcome, LiveError> {
        self.copy_base_counts();
        let outcome = self.run.finish(started, None)?;
        self.summary.filter = outcome.summary;
        self.summary.devices = self
            .counters
            .iter()
            .map(|(k, v)| (*k, serde_json::to_value(v).unwrap_or_default()))
            .collect();
        Ok(LiveOutcome {
            summary: self.summary,
            failure,
        })
    }
}

fn status(device: &str, level: u8, text: &str, values: Vec<KeyValue>) -> DiagnosticStatus {
    DiagnosticStatus {
        level,
        name: format!("ekf/{device}"),
        message: text.into(),
        hardware_id: device.into(),
        values,
    }
}

#[cfg(test)]
mod forecast_tests {
    //! `Run::forecast` over the messages `ekf live` makes.
    use super::messages::{self, Recorder};
    use crate::devices::modbus_base::WheelTicks;
    use ekf_ros::config::Config;
    use ekf_ros::replay::{Mode, Preamble, ReplayOptions, Run};
    use ekf_ros::ros2::{AnyMessage, RosMessage, Stamped};
    use std::path::Path;

    fn run(config: &Config) -> Run<'_> {
        let options = ReplayOptions {
            mode: Mode::Compass,
            map: None,
            init_from_truth: false,
            out_mcap: None,
            tum: None,
            keep_trajectories: false,
            global: false,
            grow_map: false,
        };
        let preamble = Preamble {
            scan_frame: None,
            transforms: Vec::new(),
            first_reference: None,
        };
        let t = &config.topics.joint_states;
        Run::start(config, &options, &preamble, true, "test", t, 0).unwrap()
    }

    fn feed<M: RosMessage + Stamped + Clone + Into<AnyMessage>>(
        run: &mut Run<'_>,
        recorder: &mut Recorder,
        topic: &str,
        m: &M,
    ) {
        let at = recorder.record(None, topic, m).unwrap();
        run.handle_decoded(&at.channel, at.log_time, at.log_time, m.clone().into())
            .unwrap();
    }

    #[test]
    fn a_forecast_is_the_state_fusing_the_wheel_readings_would_give() {
        let config = Config::default();
        let (mut fused, mut all) = (run(&config), run(&config));
        let mut recorder = Recorder::new(Path::new("test"));
        // Wheel readings every 0.1 s of a robot turning left; a compass heading between
        // the second and third, so the third is predicted only over its last half.
        let joints: Vec<_> = (0..6)
            .map(|i| {
                let ticks = WheelTicks {
                    left: 40 * i,
                    right: 55 * i,
                };
                messages::joint_state(&config, 1_000_000_000 + i as u64 * 100_000_000, ticks)
            })
            .collect();
        // A bearing of 90° less a little: heading 0.02 rad, within the gate.
        let bearing = std::f64::consts::FRAC_PI_2 - 0.02;
        let heading = messages::compass(&config, 1_150_000_000, bearing);
        let (topic, compass) = (&config.topics.joint_states, &config.topics.compass);
        assert_eq!(fused.forecast(&joints).unwrap(), None, "nothing fused yet");
        for run in [&mut fused, &mut all] {
            feed(run, &mut recorder, topic, &joints[0]);
            feed(run, &mut recorder, topic, &joints[1]);
            feed(run, &mut recorder, compass, &heading);
        }
        for j in &joints[2..] {
            feed(&mut all, &mut recorder, topic, j);
        }
        assert_eq!(fused.fuser().counts().compass.accepted, 1);
        let before = *fused.filter().ekf();
        let forecast = fused.forecast(&joints[2..]).unwrap().unwrap();

        assert_eq!(
            *fused.filter().ekf(),
            before,
            "the filter is left as it was"
        );
        assert_eq!(forecast.fused_ns, 1_150_000_000);
        assert_eq!(forecast.t_ns, 1_500_000_000);
        assert_eq!(forecast.pose, all.filter().pose());
        assert_eq!(forecast.covariance, *all.filter().covariance());
        assert!(
            forecast.pose.theta > before.pose().theta + 0.01,
            "it turned"
        );
        // Nothing held back: the fused state at its own time.
        let now = fused.forecast(&[]).unwrap().unwrap();
        assert_eq!((now.t_ns, now.pose), (1_150_000_000, before.pose()));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn events_and_summary_as_printed() {
        let pose = LiveEvent::Pose {
            t_ns: 12_345_000_000,
            fused_ns: 12_245_000_000,
            pose: Pose2::new(1.5, -2.25, std::f64::consts::FRAC_PI_2),
            covariance: Matrix3::from_diagonal(&nalgebra::Vector3::new(0.0009, 0.0016, 0.0001)),
        };
        assert_eq!(
            pose.to_string(),
            "12.345  x    1.500 m  y   -2.250 m  θ   90.00°  σxy 0.050 m  (odometry since 0.10 s)"
        );
        let json = pose.pose_json().unwrap();
        assert_eq!(json["t_ns"], 12_345_000_000u64);
        assert_eq!(json["sigma_xy"][1], 0.04);
        assert_eq!(json["sigma_theta"], 0.01);
        let warning = LiveEvent::Device {
            device: "base",
            level: 1,
            text: "base: no reply".into(),
        };
        assert_eq!(warning.to_string(), "warning: base: no reply");
        assert_eq!(warning.pose_json(), None);
        let mut filter = ReplaySummary {
            motion_steps: 10,
            ..Default::default()
        };
        filter.lines.scans = 4;
        filter.lines.scans_used = 3;
        filter.lines.fused = 7;
        filter.compass.accepted = 2;
        let summary = LiveSummary {
            filter,
            devices: BTreeMap::from([("laser", serde_json::json!({"scans": 4}))]),
            reconnects: BTreeMap::from([("base", 1)]),
            base_repeated_samples: 0,
            base_missed_samples: 0,
            base_implausible_samples: 0,
            base_outages_bridged: 0,
            base_restarts: 0,
            compass_invalid: 0,
            gps_fixes: 0,
            late_readings: 0,
            recording: Some("run.mcap: 40 messages".into()),
        };
        assert_eq!(
            summary.to_string(),
            "live: motion steps 10, scans 4 (used 3), lines fused 7, compass fused 2\n  \
             laser: {\"scans\":4}\n  base: reconnected 1 times\n  recording: run.mcap: 40 \
             messages\n"
        );
    }
}
