//! One thread per device: connects, reads, and on failure says so and reconnects with
//! exponential backoff. Readings and status go to the main loop over a channel; a device
//! that cannot be reached at start-up ends the run with its error.

use crate::devices::gps::{Fix, NmeaCounters, NmeaReader, Sentence};
use crate::devices::modbus_base::{
    BaseClient, BaseConfig, BaseCounters, BaseReading, REQUEST_CHARACTERS,
};
use crate::devices::sick::{RangeUnit, SickConfig, SickCounters, SickLaser};
use crate::devices::{DeviceError, Link, SerialLink};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::Sender;
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// First wait before reconnecting; doubled after each failed attempt up to
/// [`MAX_BACKOFF`].
pub(crate) const FIRST_BACKOFF: Duration = Duration::from_millis(250);
/// Longest wait between reconnection attempts.
pub(crate) const MAX_BACKOFF: Duration = Duration::from_secs(4);

/// Diagnostic levels (`diagnostic_msgs/DiagnosticStatus`).
pub(crate) const OK: u8 = 0;
/// Something is wrong but the run goes on.
pub(crate) const WARN: u8 = 1;

/// A device's measurement.
pub(crate) enum Data {
    /// A laser scan of the configured variant.
    Scan {
        /// Ranges (m).
        ranges: Vec<f32>,
        /// The unit the scanner sent them in (bits 14-15 of the count word): it sets
        /// the scan's range limits.
        unit: RangeUnit,
    },
    /// A read of the base controller's registers, with the number of the connection it
    /// came over (a reconnected controller may have restarted its counts).
    Base {
        /// The registers.
        reading: BaseReading,
        /// 0 for the first connection, +1 for each reconnection.
        connection: u64,
    },
    /// A GPS fix.
    Fix(Fix),
}

/// What a device thread hands to the main loop.
pub(crate) enum Reading {
    /// A measurement, and when it was made: the laser's sweep, the base's or the GPS's
    /// reply as the worker received it (not when the main loop gets to it).
    Data {
        /// When.
        at: Instant,
        /// What.
        data: Data,
    },
    /// The device's state changed (connected, lost, reconnected).
    Status {
        /// `laser`, `base` or `gps`.
        device: &'static str,
        /// OK or WARN.
        level: u8,
        /// What happened.
        text: String,
        /// With OK: the longest time from a measurement to its reception on this
        /// connection (the laser's telegram on the line).
        latency: Duration,
    },
    /// The device's counters since its last (re)connection.
    Counters(DeviceCounters),
    /// The device could not be reached at start-up.
    Failed(DeviceError),
}

/// Counters of one device.
#[derive(Debug, Clone, Copy, serde::Serialize)]
#[serde(untagged)]
pub(crate) enum DeviceCounters {
    /// The laser's.
    Laser(SickCounters),
    /// The base controller's.
    Base(BaseCounters),
    /// The GPS's.
    Gps(NmeaCounters),
}

/// A device as the worker drives it.
pub(crate) trait LiveDevice: Sized {
    /// `laser`, `base` or `gps`.
    const NAME: &'static str;
    /// What connecting needs.
    type Settings: Send + 'static;
    /// Opens the port and brings the device up; a silent device is an error.
    fn connect(port: &str, settings: &Self::Settings) -> Result<Self, DeviceError>;
    /// Reads the next readings into `out`; `connection` counts reconnections.
    fn next(&mut self, out: &mut Vec<Reading>, connection: u64) -> Result<(), DeviceError>;
    /// Counts so far.
    fn counters(&self) -> DeviceCounters;
    /// A line about the connection, e.g. the baud rate.
    fn describe(&self) -> String;
    /// The longest time from a measurement to its reception.
    fn latency(&self) -> Duration {
        Duration::ZERO
    }
    /// Leaves the device as it should be left (the laser stops its output).
    fn close(self) {}
}

/// Starts a worker for `D` on `port`.
pub(crate) fn spawn<D: LiveDevice + 'static>(
    port: String,
    settings: D::Settings,
    tx: Sender<Reading>,
    stop: Arc<AtomicBool>,
) -> JoinHandle<()> {
    std::thread::spawn(move || work::<D>(&port, &settings, &tx, &stop))
}

fn status(tx: &Sender<Reading>, device: &'static str, level: u8, text: String) {
    connected(tx, device, level, text, Duration::ZERO);
}

fn connected(
    tx: &Sender<Reading>,
    device: &'static str,
    level: u8,
    text: String,
    latency: Duration,
) {
    let _ = tx.send(Reading::Status {
        device,
        level,
        text,
        latency,
    });
}

fn work<D: LiveDevice>(
    port: &str,
    settings: &D::Settings,
    tx: &Sender<Reading>,
    stop: &AtomicBool,
) {
    let mut device = match D::connect(port, settings) {
        Ok(d) => d,
        Err(e) => {
            let _ = tx.send(Reading::Failed(e));
            return;
        }
    };
    connected(
        tx,
        D::NAME,
        OK,
        format!("{} on {port}: {}", D::NAME, device.describe()),
        device.latency(),
    );
    let mut out = Vec::new();
    let mut connection = 0;
    loop {
        if stop.load(Ordering::Relaxed) {
            device.close();
            return;
        }
        let step = device.next(&mut out, connection);
        for r in out.drain(..) {
            if tx.send(r).is_err() {
                return;
            }
        }
        let _ = tx.send(Reading::Counters(device.counters()));
        if let Err(e) = step {
            status(tx, D::NAME, WARN, format!("{e}; reconnecting"));
            drop(device);
            match reconnect::<D>(port, settings, tx, stop) {
                Some(d) => {
                    device = d;
                    connection += 1;
                }
                None => return,
            }
        }
    }
}

/// Retries with exponential backoff until the device is back or the run stops.
fn reconnect<D: LiveDevice>(
    port: &str,
    settings: &D::Settings,
    tx: &Sender<Reading>,
    stop: &AtomicBool,
) -> Option<D> {
    let mut backoff = FIRST_BACKOFF;
    loop {
        let until = Instant::now() + backoff;
        while Instant::now() < until {
            if stop.load(Ordering::Relaxed) {
                return None;
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        match D::connect(port, settings) {
            Ok(d) => {
                connected(
                    tx,
                    D::NAME,
                    OK,
                    format!("{} on {port}: back: {}", D::NAME, d.describe()),
                    d.latency(),
                );
                return Some(d);
            }
            Err(e) => {
                backoff = (backoff * 2).min(MAX_BACKOFF);
                status(
                    tx,
                    D::NAME,
                    WARN,
                    format!("{e}; next try in {:.2} s", backoff.as_secs_f64()),
                );
            }
        }
    }
}

/// The laser worker's device.
pub(crate) struct Laser(SickLaser<SerialLink>);

impl LiveDevice for Laser {
    const NAME: &'static str = "laser";
    type Settings = SickConfig;

    fn connect(port: &str, settings: &SickConfig) -> Result<Self, DeviceError> {
        let link = SerialLink::open(Self::NAME, port, 9600)?;
        SickLaser::connect(link, *settings).map(Laser)
    }

    fn next(&mut self, out: &mut Vec<Reading>, _: u64) -> Result<(), DeviceError> {
        let scan = self.0.next_scan()?;
        out.push(Reading::Data {
            at: scan.measured,
            data: Data::Scan {
                ranges: scan.values.ranges(),
                unit: scan.values.unit,
            },
        });
        Ok(())
    }

    fn latency(&self) -> Duration {
        self.0.latency()
    }

    fn counters(&self) -> DeviceCounters {
        DeviceCounters::Laser(self.0.counters())
    }

    fn describe(&self) -> String {
        format!(
            "scanning {}° at {}° and {} baud",
            self.0.variant().angle_deg,
            f64::from(self.0.variant().resolution_cdeg) / 100.0,
            self.0.baud_rate().bits_per_second()
        )
    }

    fn close(self) {
        // Best effort: the line may already be gone.
        let _ = self.0.stop();
    }
}

/// What the base worker needs.
pub(crate) struct BaseSettings {
    /// The client's settings.
    pub(crate) client: BaseConfig,
    /// Baud rate.
    pub(crate) baud: u32,
    /// Time between polls.
    pub(crate) period: Duration,
}

/// The base worker's device: polls at a fixed rate.
pub(crate) struct Base {
    client: BaseClient<SerialLink>,
    period: Duration,
    next_poll: Instant,
    /// A request's time on the line, from its start to the controller's latch.
    request_time: Duration,
}

impl LiveDevice for Base {
    const NAME: &'static str = "base";
    type Settings = BaseSettings;

    fn connect(port: &str, settings: &BaseSettings) -> Result<Self, DeviceError> {
        let link = SerialLink::open(Self::NAME, port, settings.baud)?;
        let mut client = BaseClient::new(link, settings.client);
        // The controller must answer before the run starts (a silent one is an error).
        while client.poll()?.is_none() {}
        // 10 bits a character (start, 8 data, stop).
        let request_time =
            Duration::from_secs_f64(REQUEST_CHARACTERS * 10.0 / f64::from(settings.baud.max(1)));
        Ok(Base {
            client,
            period: settings.period,
            next_poll: Instant::now(),
            request_time,
        })
    }

    fn next(&mut self, out: &mut Vec<Reading>, connection: u64) -> Result<(), DeviceError> {
        let now = Instant::now();
        if self.next_poll > now {
            std::thread::sleep(self.next_poll - now);
        }
        self.next_poll += self.period;
        if self.next_poll < Instant::now() {
            // Fell behind (a slow reply): poll on from now rather than in a burst.
            self.next_poll = Instant::now() + self.period;
        }
        if let Some(reading) = self.client.poll()? {
            out.push(Reading::Data {
                // When the controller latched the sample: the request's arrival, not the
                // reply's (which a busy host may read late).
                at: self.client.last_request() + self.request_time,
                data: Data::Base {
                    reading,
                    connection,
                },
            });
        }
        Ok(())
    }

    fn counters(&self) -> DeviceCounters {
        DeviceCounters::Base(self.client.counters())
    }

    fn describe(&self) -> String {
        format!(
            "answering, polled every {:.0} ms",
            self.period.as_secs_f64() * 1e3
        )
    }
}

/// What the GPS worker needs.
pub(crate) struct GpsSettings {
    /// Baud rate.
    pub(crate) baud: u32,
    /// Longest time without a valid sentence.
    pub(crate) timeout: Duration,
}

/// The GPS worker's device: reads NMEA lines.
pub(crate) struct Gps {
    link: SerialLink,
    reader: NmeaReader,
    timeout: Duration,
    last_valid: Instant,
    baud: u32,
}

impl Gps {
    /// Reads what is there; `true` if a valid sentence came.
    fn read(&mut self, out: &mut Vec<Reading>) -> Result<bool, DeviceError> {
        let mut buf = [0u8; 512];
        let n = self
            .link
            .read_some(&mut buf)
            .map_err(|source| DeviceError::Io {
                device: Self::NAME,
                port: self.link.name().into(),
                during: "reading",
                source,
            })?;
        let at = Instant::now();
        let mut valid = false;
        for s in self.reader.push(&buf[..n]) {
            match s {
                Sentence::Fix(f) => {
                    out.push(Reading::Data {
                        at,
                        data: Data::Fix(f),
                    });
                    valid = true;
                }
                Sentence::NoFix | Sentence::Other => valid = true,
                Sentence::Invalid(_) => {}
            }
        }
        if valid {
            self.last_valid = Instant::now();
        } else if self.last_valid.elapsed() >= self.timeout {
            return Err(DeviceError::Silent {
                device: Self::NAME,
                port: self.link.name().into(),
                waited: self.last_valid.elapsed(),
                expected: format!("NMEA sentences (GGA, RMC) at {} baud", self.baud),
            });
        }
        Ok(valid)
    }
}

impl LiveDevice for Gps {
    const NAME: &'static str = "gps";
    type Settings = GpsSettings;

    fn connect(port: &str, settings: &GpsSettings) -> Result<Self, DeviceError> {
        let mut gps = Gps {
            link: SerialLink::open(Self::NAME, port, settings.baud)?,
            reader: NmeaReader::new(),
            timeout: settings.timeout,
            last_valid: Instant::now(),
            baud: settings.baud,
        };
        // Fixes before the run starts are not used; the first valid sentence proves the
        // receiver is there.
        let mut discard = Vec::new();
        while !gps.read(&mut discard)? {}
        Ok(gps)
    }

    fn next(&mut self, out: &mut Vec<Reading>, _: u64) -> Result<(), DeviceError> {
        self.read(out).map(|_| ())
    }

    fn counters(&self) -> DeviceCounters {
        DeviceCounters::Gps(self.reader.counters)
    }

    fn describe(&self) -> String {
        format!("NMEA at {} baud", self.baud)
    }
}
