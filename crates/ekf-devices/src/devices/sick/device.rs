//! The scanner side of the LMS 2xx protocol, for emulators: answers mode, baud-rate and
//! variant requests as the scanner does (ACK, then the reply telegram) and turns ranges
//! into `B0` telegrams while continuous output is on. Starts as after power-up.

use super::measured::{MeasuredValues, RangeUnit};
use super::parser::{Event, TelegramParser};
use super::telegram::{
    BaudRate, Mode, Telegram, Variant, ACK, CMD_MODE, CMD_VARIANT, NAK, REPLY_MEASURED, REPLY_MODE,
    REPLY_VARIANT,
};

/// The STATUS byte the emulated scanner sends: no error.
const STATUS_OK: u8 = 0x10;

/// Ranges of one sweep in the laser frame (ROS convention: counter-clockwise from
/// `angle_min`, x forward), in metres; non-finite for no return.
#[derive(Debug, Clone, PartialEq)]
pub struct Sweep {
    /// Bearing of the first range (rad).
    pub angle_min: f64,
    /// Angle between ranges (rad).
    pub angle_increment: f64,
    /// Ranges (m).
    pub ranges: Vec<f64>,
}

impl Sweep {
    /// The range nearest to `bearing` (rad), or ∞ outside the sweep.
    fn nearest(&self, bearing: f64) -> f64 {
        let i = ((bearing - self.angle_min) / self.angle_increment).round();
        if i >= 0.0 && (i as usize) < self.ranges.len() {
            self.ranges[i as usize]
        } else {
            f64::INFINITY
        }
    }
}

/// An emulated LMS 2xx.
#[derive(Debug)]
pub struct SickScanner {
    parser: TelegramParser,
    baud: BaudRate,
    variant: Variant,
    continuous: bool,
    unit: RangeUnit,
}

impl SickScanner {
    /// A scanner just powered up: 9600 baud, 180° at 0.5°, no continuous output.
    pub fn new(unit: RangeUnit) -> Self {
        Self {
            parser: TelegramParser::new(),
            baud: BaudRate::B9600,
            variant: Variant::DEFAULT,
            continuous: false,
            unit,
        }
    }

    /// The rate the scanner speaks now.
    pub fn baud_rate(&self) -> BaudRate {
        self.baud
    }

    /// The angle and resolution it scans.
    pub fn variant(&self) -> Variant {
        self.variant
    }

    /// Whether continuous output is on.
    pub fn is_continuous(&self) -> bool {
        self.continuous
    }

    /// Takes bytes from the host; returns what the scanner sends back (ACK/NAK and
    /// replies), in order.
    pub fn receive(&mut self, bytes: &[u8]) -> Vec<u8> {
        self.parser.push(bytes);
        let mut out = Vec::new();
        while let Some(event) = self.parser.next_event() {
            if let Event::Telegram(t) = event {
                out.extend(self.answer(&t));
            }
        }
        out
    }

    /// The `B0` telegram for `sweep` if continuous output is on.
    pub fn scan(&self, sweep: &Sweep) -> Option<Telegram> {
        self.continuous.then(|| {
            let v = self.variant;
            let first = -(f64::from(v.angle_deg) / 2.0).to_radians();
            let step = (f64::from(v.resolution_cdeg) / 100.0).to_radians();
            let values = (0..v.values())
                .map(|i| {
                    let range = sweep.nearest(first + step * i as f64);
                    MeasuredValues::value_of(range, self.unit)
                })
                .collect();
            let m = MeasuredValues {
                unit: self.unit,
                values,
            };
            Telegram::reply(REPLY_MEASURED, &m.encode(), STATUS_OK)
        })
    }

    fn answer(&mut self, request: &Telegram) -> Vec<u8> {
        let reply = match request.command {
            CMD_MODE => request
                .data
                .first()
                .and_then(|c| Mode::from_code(*c))
                .map(|mode| {
                    let reply = Telegram::reply(REPLY_MODE, &[0x00], STATUS_OK);
                    match mode {
                        Mode::Continuous => self.continuous = true,
                        Mode::Stop => self.continuous = false,
                        Mode::Baud(b) => self.baud = b,
                    }
                    reply
                }),
            CMD_VARIANT => Variant::from_bytes(&request.data).map(|v| {
                let ok = v.is_supported();
                if ok {
                    self.variant = v;
                }
                let mut data = vec![u8::from(ok)];
                data.extend_from_slice(&self.variant.request().data);
                Telegram::reply(REPLY_VARIANT, &data, STATUS_OK)
            }),
            _ => None,
        };
        match reply {
            Some(t) => {
                let mut out = vec![ACK];
                out.extend(t.encode());
                out
            }
            None => vec![NAK],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::driver::{SickConfig, SickLaser};
    use super::*;
    use crate::devices::Link;
    use std::collections::VecDeque;
    use std::io;

    /// A link wired straight to an emulated scanner, no I/O: the driver's side of the
    /// conversation, with the scanner's answers queued.
    struct Wire {
        scanner: SickScanner,
        to_host: VecDeque<u8>,
        host_baud: u32,
        sweeps: usize,
        /// Bytes on the line before the answer to the next request.
        inject: Vec<u8>,
    }

    impl Link for Wire {
        fn read_some(&mut self, buf: &mut [u8]) -> io::Result<usize> {
            let same_rate = self.host_baud == self.scanner.baud_rate().bits_per_second();
            if self.to_host.is_empty() && self.sweeps > 0 && self.scanner.is_continuous() {
                let sweep = Sweep {
                    angle_min: -1.6,
                    angle_increment: 0.01,
                    ranges: vec![2.0; 321],
                };
                match self.scanner.scan(&sweep) {
                    // At another rate the host sees noise.
                    Some(_) if !same_rate => self.to_host.extend([0xff, 0x00, 0xfe]),
                    Some(t) => {
                        self.sweeps -= 1;
                        self.to_host.extend(t.encode());
                    }
                    None => {}
                }
            }
            let n = buf.len().min(self.to_host.len());
            for (b, v) in buf.iter_mut().zip(self.to_host.drain(..n)) {
                *b = v;
            }
            Ok(n)
        }
        fn write_all_bytes(&mut self, bytes: &[u8]) -> io::Result<()> {
            // Bytes sent at a rate the scanner does not speak arrive as noise: dropped.
            if self.host_baud == self.scanner.baud_rate().bits_per_second() {
                let answer = self.scanner.receive(bytes);
                self.to_host.extend(std::mem::take(&mut self.inject));
                self.to_host.extend(answer);
            }
            Ok(())
        }
        fn set_baud_rate(&mut self, bps: u32) -> io::Result<()> {
            self.host_baud = bps;
            Ok(())
        }
        fn clear_input(&mut self) -> io::Result<()> {
            self.to_host.clear();
            Ok(())
        }
        fn name(&self) -> &str {
            "wire"
        }
    }

    fn config() -> SickConfig {
        SickConfig {
            reply_timeout: std::time::Duration::from_millis(50),
            ..SickConfig::default()
        }
    }

    #[test]
    fn driver_and_scanner_agree() {
        let wire = Wire {
            scanner: SickScanner::new(RangeUnit::Millimetres),
            to_host: VecDeque::new(),
            host_baud: 0,
            sweeps: 2,
            inject: Vec::new(),
        };
        let mut laser = SickLaser::connect(wire, config()).unwrap();
        assert_eq!(laser.baud_rate(), BaudRate::B38400);
        let scan = laser.next_scan().unwrap().values;
        assert_eq!(scan.values.len(), 361);
        // Every beam of 180° lies inside the sweep's ±1.6 rad: 2 m everywhere.
        assert!(scan.ranges().iter().all(|r| (r - 2.0).abs() < 1e-6));
        laser.next_scan().unwrap();
        assert_eq!(laser.counters().scans, 2);
        let wire = laser.stop().unwrap();
        assert!(!wire.scanner.is_continuous());
    }

    #[test]
    fn a_scanner_left_at_38400_is_found() {
        let mut scanner = SickScanner::new(RangeUnit::Centimetres);
        scanner.receive(&Mode::Baud(BaudRate::B38400).request().encode());
        scanner.receive(&Mode::Continuous.request().encode());
        let wire = Wire {
            scanner,
            to_host: VecDeque::new(),
            host_baud: 0,
            sweeps: 3,
            inject: Vec::new(),
        };
        let mut laser = SickLaser::connect(
            wire,
            SickConfig {
                baud: BaudRate::B500000,
                ..config()
            },
        )
        .unwrap();
        assert_eq!(laser.baud_rate(), BaudRate::B500000);
        assert!(laser.next_scan().is_ok());
    }

    #[test]
    fn unsupported_variant_is_refused_by_name() {
        let wire = Wire {
            scanner: SickScanner::new(RangeUnit::Millimetres),
            to_host: VecDeque::new(),
            host_baud: 0,
            sweeps: 0,
            inject: Vec::new(),
        };
        let Err(e) = SickLaser::connect(
            wire,
            SickConfig {
                variant: Variant {
                    angle_deg: 180,
                    resolution_cdeg: 25,
                },
                ..config()
            },
        ) else {
            panic!("180° at 0.25° must be refused");
        };
        assert!(
            e.to_string()
                .contains("refused angle 180° at resolution 0.25°"),
            "{e}"
        );
    }

    #[test]
    fn a_reply_behind_a_false_stx_is_found_when_the_line_goes_quiet() {
        // The stop request lands while a scan is going out: the rest of its range data
        // holds 02 80 10 01, an STX with a declared length of 272 bytes, then come the ACK
        // and the A0 reply, then nothing.
        let wire = Wire {
            scanner: SickScanner::new(RangeUnit::Millimetres),
            to_host: VecDeque::new(),
            host_baud: 0,
            sweeps: 1,
            inject: vec![0x10, 0x02, 0x80, 0x10, 0x01, 0x33, 0x44],
        };
        let mut laser = SickLaser::connect(wire, config()).unwrap();
        assert_eq!(laser.baud_rate(), BaudRate::B38400);
        assert!(laser.counters().parser.truncated >= 1);
        let scan = laser.next_scan().unwrap();
        assert_eq!(scan.values.values.len(), 361);
        // Stamped at the middle of its sweep: the telegram's time on the line and half
        // the sweep before its arrival.
        assert_eq!(scan.received - scan.measured, laser.latency());
    }
}
