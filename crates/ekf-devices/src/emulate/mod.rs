//! Emulators of the robot's three devices on pseudo-terminals: the device side of each
//! protocol, fed with [`RobotSample`]s (by a test, or by the simulator), with fault
//! injection. Each device is reached through a stable symlink that survives an emulated
//! unplug/replug, as `/dev/serial/by-id` links do for real adapters.

mod devices;
mod faults;
mod pty;
pub mod robot;
mod runner;

pub use faults::Fault;

use crate::devices::sick::device::Sweep;
use crate::devices::sick::RangeUnit;
use runner::Command;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::Sender;
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// What the robot's devices measure at one instant.
#[derive(Debug, Clone, PartialEq)]
pub struct RobotSample {
    /// Time (ns), for the GPS clock.
    pub t_ns: u64,
    /// Left encoder count (wraps at 2³² like the controller's counter).
    pub left_ticks: u32,
    /// Right encoder count.
    pub right_ticks: u32,
    /// Compass bearing (degrees clockwise from magnetic north).
    pub bearing_deg: f64,
    /// How the encoder counts and the bearing go on until the next sample; `None`:
    /// they hold.
    pub motion: Option<Motion>,
    /// A laser sweep completed at this instant, if any.
    pub sweep: Option<Sweep>,
    /// What the GPS reports at this instant, if anything.
    pub gps: Option<GpsReport>,
}

/// The encoders and the compass between two samples: the base controller latches them
/// whenever it is polled, so a poll between samples sees them interpolated linearly in
/// time, as real encoders count on between a simulator's steps.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Motion {
    /// When the sample holds.
    pub at: Instant,
    /// Time from the sample to the next one.
    pub duration: Duration,
    /// Left encoder count at the next sample.
    pub left_ticks: u32,
    /// Right encoder count at the next sample.
    pub right_ticks: u32,
    /// Change of the bearing until the next sample (degrees, clockwise positive).
    pub bearing_change_deg: f64,
}

impl RobotSample {
    /// Encoder counts `(left, right)` and bearing (degrees in `[0, 360)`) at `now`:
    /// the sample's, moved on by [`Motion`] (held at the next sample's after it).
    pub fn base_state_at(&self, now: Instant) -> (u32, u32, f64) {
        let Some(m) = &self.motion else {
            return (
                self.left_ticks,
                self.right_ticks,
                self.bearing_deg.rem_euclid(360.0),
            );
        };
        let f = if m.duration.is_zero() {
            1.0
        } else {
            (now.saturating_duration_since(m.at).as_secs_f64() / m.duration.as_secs_f64()).min(1.0)
        };
        let ticks = |from: u32, to: u32| {
            // The shorter way round a 32-bit counter; floor as the counter counts whole ticks.
            let delta = f64::from(to.wrapping_sub(from) as i32);
            from.wrapping_add((delta * f).floor() as i32 as u32)
        };
        (
            ticks(self.left_ticks, m.left_ticks),
            ticks(self.right_ticks, m.right_ticks),
            (self.bearing_deg + m.bearing_change_deg * f).rem_euclid(360.0),
        )
    }
}

/// What the GPS receiver says.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum GpsReport {
    /// A position fix.
    Fix(GeoFix),
    /// Sentences without a fix (indoors, no satellites in view).
    NoFix,
}

pub use ekf_ros::geo::GeoFix;

/// One of the emulated devices.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Device {
    /// The SICK LMS 2xx.
    Laser,
    /// The MODBUS base controller.
    Base,
    /// The NMEA GPS.
    Gps,
}

/// How the emulators are set up.
#[derive(Debug, Clone)]
pub struct EmulatorOptions {
    /// Folder for the device symlinks `laser`, `base`, `gps`.
    pub dir: PathBuf,
    /// Range unit of the laser's values.
    pub unit: RangeUnit,
    /// MODBUS unit id of the base controller.
    pub unit_id: u8,
}

/// The three running emulators.
pub struct Emulators {
    senders: [Sender<Command>; 3],
    ready: [Arc<AtomicBool>; 3],
    threads: Vec<JoinHandle<()>>,
    dir: PathBuf,
}

impl Emulators {
    /// Creates the pseudo-terminals and their symlinks and starts the device threads.
    pub fn start(options: &EmulatorOptions) -> std::io::Result<Self> {
        ekf_ros::output_dir::create_output_dir(&options.dir)?;
        let laser = devices::Laser::new(options.unit);
        let base = devices::Base::new(options.unit_id);
        let gps = devices::Gps;
        let ready: [Arc<AtomicBool>; 3] = Default::default();
        let (l, lt) = runner::spawn(laser, options.dir.join("laser"), Arc::clone(&ready[0]))?;
        let (b, bt) = runner::spawn(base, options.dir.join("base"), Arc::clone(&ready[1]))?;
        let (g, gt) = runner::spawn(gps, options.dir.join("gps"), Arc::clone(&ready[2]))?;
        Ok(Self {
            senders: [l, b, g],
            ready,
            threads: vec![lt, bt, gt],
            dir: options.dir.clone(),
        })
    }

    /// The symlink through which `device` is reached.
    pub fn path(&self, device: Device) -> PathBuf {
        self.dir.join(match device {
            Device::Laser => "laser",
            Device::Base => "base",
            Device::Gps => "gps",
        })
    }

    /// Whether a host has brought `device` into operation since it last powered up:
    /// the laser streams (continuous output on), the base controller has answered a
    /// poll; the GPS needs nothing.
    pub fn ready(&self, device: Device) -> bool {
        self.ready[device as usize].load(Ordering::Relaxed)
    }

    /// Hands a new sample to every device.
    pub fn sample(&self, sample: RobotSample) {
        let sample = Arc::new(sample);
        for s in &self.senders {
            // A device thread that ended has nothing to emulate any more.
            let _ = s.send(Command::Sample(Arc::clone(&sample)));
        }
    }

    /// Injects a fault into one device; returns once the device has taken it on (a
    /// device thread that has ended takes nothing).
    pub fn fault(&self, device: Device, fault: Fault) {
        let (done, taken) = std::sync::mpsc::channel();
        if self.senders[device as usize]
            .send(Command::Fault(fault, done))
            .is_ok()
        {
            let _ = taken.recv();
        }
    }

    /// Stops the devices and removes their symlinks.
    pub fn stop(self) {
        for s in &self.senders {
            let _ = s.send(Command::Stop);
        }
        for t in self.threads {
            let _ = t.join();
        }
    }

    /// The folder of the symlinks.
    pub fn dir(&self) -> &Path {
        &self.dir
    }
}
