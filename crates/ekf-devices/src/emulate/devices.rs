//! The three devices as the runner drives them: each answers host bytes and produces its
//! unsolicited output from robot samples, using the device side of its protocol.

use super::{GpsReport, RobotSample};
use crate::devices::gps::device::{no_fix_sentences, sentences};
use crate::devices::modbus_base::device::{BaseController, BaseState};
use crate::devices::sick::device::SickScanner;
use crate::devices::sick::RangeUnit;
use std::time::{Duration, Instant};

/// What the runner needs from an emulated device.
pub(crate) trait Emulated: Send + 'static {
    /// Back to the power-up state (after an emulated replug).
    fn power_up(&mut self);
    /// Answers bytes from the host, given the latest sample.
    fn answer(&mut self, bytes: &[u8], sample: Option<&RobotSample>) -> Vec<Vec<u8>>;
    /// Output the device sends by itself when a new sample arrives.
    fn output(&mut self, sample: &RobotSample) -> Option<Vec<u8>>;
    /// Time from a sample to the moment its output is ready to be sent (the laser: the
    /// second half of its sweep; the sample is the sweep's middle).
    fn output_delay(&self) -> Duration {
        Duration::ZERO
    }
    /// Time `bytes` bytes take on the device's line (the laser's; the others are
    /// delivered at once).
    fn line_time(&self, _bytes: usize) -> Duration {
        Duration::ZERO
    }
    /// Index of a checksum byte in an output (binary protocols: the last byte).
    fn checksum_at(&self, out: &[u8]) -> usize {
        out.len().saturating_sub(1)
    }
    /// Whether a host has brought the device into operation (see [`super::Emulators::ready`]).
    fn host_ready(&self) -> bool {
        true
    }
    /// Injects a MODBUS exception into the next reply; `false` if the device has none.
    fn fail_next(&mut self, _code: u8) -> bool {
        false
    }
}

/// The SICK LMS 2xx.
pub(crate) struct Laser {
    scanner: SickScanner,
    unit: RangeUnit,
}

impl Laser {
    pub(crate) fn new(unit: RangeUnit) -> Self {
        Self {
            scanner: SickScanner::new(unit),
            unit,
        }
    }
}

impl Emulated for Laser {
    fn power_up(&mut self) {
        self.scanner = SickScanner::new(self.unit);
    }

    fn answer(&mut self, bytes: &[u8], _: Option<&RobotSample>) -> Vec<Vec<u8>> {
        let out = self.scanner.receive(bytes);
        if out.is_empty() {
            Vec::new()
        } else {
            vec![out]
        }
    }

    fn host_ready(&self) -> bool {
        self.scanner.is_continuous()
    }

    fn output_delay(&self) -> Duration {
        self.scanner.variant().sweep_duration() / 2
    }

    fn line_time(&self, bytes: usize) -> Duration {
        self.scanner.baud_rate().transmission_time(bytes)
    }

    fn output(&mut self, sample: &RobotSample) -> Option<Vec<u8>> {
        let sweep = sample.sweep.as_ref()?;
        self.scanner.scan(sweep).map(|t| t.encode())
    }
}

/// The base controller.
pub(crate) struct Base {
    controller: BaseController,
    unit_id: u8,
    answered: bool,
}

impl Base {
    pub(crate) fn new(unit_id: u8) -> Self {
        Self {
            controller: BaseController::new(unit_id),
            unit_id,
            answered: false,
        }
    }
}

impl Emulated for Base {
    fn power_up(&mut self) {
        // The encoder counts live in the samples: an unplugged cable does not reset them.
        self.controller = BaseController::new(self.unit_id);
        self.answered = false;
    }

    fn host_ready(&self) -> bool {
        self.answered
    }

    fn answer(&mut self, bytes: &[u8], sample: Option<&RobotSample>) -> Vec<Vec<u8>> {
        // The controller latches the encoders and the compass now.
        let state = sample.map_or(BaseState::default(), |s| {
            let (left_ticks, right_ticks, bearing_deg) = s.base_state_at(Instant::now());
            BaseState {
                left_ticks,
                right_ticks,
                bearing_tenths: bearing_tenths(bearing_deg),
            }
        });
        let replies = self.controller.receive(bytes, state);
        self.answered |= !replies.is_empty();
        replies
    }

    fn output(&mut self, _: &RobotSample) -> Option<Vec<u8>> {
        None
    }

    fn fail_next(&mut self, code: u8) -> bool {
        self.controller.fail_next(code);
        true
    }
}

/// A bearing (degrees) as the CMPS03 reports it: tenths of a degree, 0–3599.
pub(crate) fn bearing_tenths(bearing_deg: f64) -> u16 {
    ((bearing_deg.rem_euclid(360.0) * 10.0).round() as u16) % 3600
}

/// The NMEA GPS: GGA and RMC for every sample with a GPS report.
pub(crate) struct Gps;

impl Emulated for Gps {
    fn power_up(&mut self) {}

    fn answer(&mut self, _: &[u8], _: Option<&RobotSample>) -> Vec<Vec<u8>> {
        Vec::new()
    }

    fn output(&mut self, sample: &RobotSample) -> Option<Vec<u8>> {
        let utc_s = (sample.t_ns % 86_400_000_000_000) as f64 * 1e-9;
        let text = match sample.gps? {
            GpsReport::Fix(f) => sentences(f.latitude, f.longitude, f.altitude, f.hdop, utc_s),
            GpsReport::NoFix => no_fix_sentences(utc_s),
        };
        Some(text.into_bytes())
    }

    /// The first digit of the first sentence's checksum (after its `*`).
    fn checksum_at(&self, out: &[u8]) -> usize {
        out.iter().position(|b| *b == b'*').map_or(0, |i| i + 1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bearings_become_cmps03_tenths() {
        assert_eq!(bearing_tenths(0.0), 0);
        assert_eq!(bearing_tenths(359.96), 0);
        assert_eq!(bearing_tenths(-0.1), 3599);
        assert_eq!(bearing_tenths(123.44), 1234);
        assert_eq!(bearing_tenths(90.0 + 360.0), 900);
    }
}
