//! `ekf live`: the filter on the robot's serial devices. Readings become the ROS 2
//! messages of docs/ARCHITECTURE.md §4, are recorded (with `/tf_static` for the laser mount and the
//! estimates) and fed to the same filter loop as `ekf replay`, so a replay of the
//! recording gives the same poses bit for bit. Devices that fail are reported and
//! reconnected with backoff; a device silent at start-up is an error naming its port.

mod clock;
pub mod messages;
mod report;
mod session;
mod workers;

pub use report::{LiveError, LiveEvent, LiveOutcome, LiveSummary};

use crate::devices::modbus_base::BaseConfig;
use crate::devices::sick::{BaudRate, SickConfig, Variant};
use clock::Clock;
use ekf_ros::config::{Config, MotionSource};
use ekf_ros::replay::Mode;
use session::Live;
use std::collections::{BTreeMap, BTreeSet};
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, RecvTimeoutError};
use std::sync::Arc;
use std::time::{Duration, Instant};
use workers::{Data, Reading};

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

/// How much longer than a device's announced latency a measurement is held before the
/// measurements made up to then are fused: covers a worker thread descheduled between
/// stamping a measurement and handing it over.
const HOLD_SLACK: Duration = Duration::from_millis(100);

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
    live.set_hold(latency.values().max().copied().unwrap_or_default());
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
                        live.set_hold(latency.values().max().copied().unwrap_or_default());
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
        // A measurement not yet handed over is made after now less the latency of
        // its device: what was made before that can be fused, in order.
        if step.is_ok() {
            step = live.release_until(Instant::now());
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
    match live.release_all() {
        Ok(()) => live.report_pose(on_event),
        Err(e) => {
            failure.get_or_insert(e);
        }
    }
    let _ = live.counters_diagnostics();
    live.finish(started, failure)
}
