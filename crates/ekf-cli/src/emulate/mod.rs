//! Emulators of the robot's three devices on pseudo-terminals: the device side of each
//! protocol, fed with [`RobotSample`]s (by a test, or by the simulator), with fault
//! injection. Each device is reached through a stable symlink that survives an emulated
//! unplug/replug, as `/dev/serial/by-id` links do for real adapters.

mod devices;
mod faults;
mod pty;
mod runner;

pub use faults::Fault;

use crate::devices::sick::device::Sweep;
use crate::devices::sick::RangeUnit;
use runner::Command;
use std::path::{Path, PathBuf};
use std::sync::mpsc::Sender;
use std::sync::Arc;
use std::thread::JoinHandle;

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
    /// A laser sweep completed at this instant, if any.
    pub sweep: Option<Sweep>,
    /// A GPS fix at this instant, if any.
    pub fix: Option<GeoFix>,
}

/// A GPS position.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GeoFix {
    /// Latitude (degrees).
    pub latitude: f64,
    /// Longitude (degrees).
    pub longitude: f64,
    /// Altitude (m).
    pub altitude: f64,
    /// Horizontal dilution of precision.
    pub hdop: f64,
}

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
    threads: Vec<JoinHandle<()>>,
    dir: PathBuf,
}

impl Emulators {
    /// Creates the pseudo-terminals and their symlinks and starts the device threads.
    pub fn start(options: &EmulatorOptions) -> std::io::Result<Self> {
        std::fs::create_dir_all(&options.dir)?;
        let laser = devices::Laser::new(options.unit);
        let base = devices::Base::new(options.unit_id);
        let gps = devices::Gps;
        let (l, lt) = runner::spawn(laser, options.dir.join("laser"))?;
        let (b, bt) = runner::spawn(base, options.dir.join("base"))?;
        let (g, gt) = runner::spawn(gps, options.dir.join("gps"))?;
        Ok(Self {
            senders: [l, b, g],
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
