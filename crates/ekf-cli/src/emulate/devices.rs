//! The three devices as the runner drives them: each answers host bytes and produces its
//! unsolicited output from robot samples, using the device side of its protocol.

use super::RobotSample;
use crate::devices::gps::device::sentences;
use crate::devices::modbus_base::device::{BaseController, BaseState};
use crate::devices::sick::device::SickScanner;
use crate::devices::sick::RangeUnit;

/// What the runner needs from an emulated device.
pub(crate) trait Emulated: Send + 'static {
    /// Back to the power-up state (after an emulated replug).
    fn power_up(&mut self);
    /// Answers bytes from the host, given the latest sample.
    fn answer(&mut self, bytes: &[u8], sample: Option<&RobotSample>) -> Vec<Vec<u8>>;
    /// Output the device sends by itself when a new sample arrives.
    fn output(&mut self, sample: &RobotSample) -> Option<Vec<u8>>;
    /// Index of a checksum byte in an output (binary protocols: the last byte).
    fn checksum_at(&self, out: &[u8]) -> usize {
        out.len().saturating_sub(1)
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

    fn output(&mut self, sample: &RobotSample) -> Option<Vec<u8>> {
        let sweep = sample.sweep.as_ref()?;
        self.scanner.scan(sweep).map(|t| t.encode())
    }
}

/// The base controller.
pub(crate) struct Base {
    controller: BaseController,
    unit_id: u8,
}

impl Base {
    pub(crate) fn new(unit_id: u8) -> Self {
        Self {
            controller: BaseController::new(unit_id),
            unit_id,
        }
    }
}

impl Emulated for Base {
    fn power_up(&mut self) {
        // The encoder counts live in the samples: an unplugged cable does not reset them.
        self.controller = BaseController::new(self.unit_id);
    }

    fn answer(&mut self, bytes: &[u8], sample: Option<&RobotSample>) -> Vec<Vec<u8>> {
        let state = sample.map_or(BaseState::default(), |s| BaseState {
            left_ticks: s.left_ticks,
            right_ticks: s.right_ticks,
            bearing_tenths: ((s.bearing_deg.rem_euclid(360.0) * 10.0).round() as u16) % 3600,
        });
        self.controller.receive(bytes, state)
    }

    fn output(&mut self, _: &RobotSample) -> Option<Vec<u8>> {
        None
    }

    fn fail_next(&mut self, code: u8) -> bool {
        self.controller.fail_next(code);
        true
    }
}

/// The NMEA GPS: GGA and RMC for every sample with a fix.
pub(crate) struct Gps;

impl Emulated for Gps {
    fn power_up(&mut self) {}

    fn answer(&mut self, _: &[u8], _: Option<&RobotSample>) -> Vec<Vec<u8>> {
        Vec::new()
    }

    fn output(&mut self, sample: &RobotSample) -> Option<Vec<u8>> {
        let f = sample.fix?;
        let utc_s = (sample.t_ns % 86_400_000_000_000) as f64 * 1e-9;
        Some(sentences(f.latitude, f.longitude, f.altitude, f.hdop, utc_s).into_bytes())
    }

    /// The first digit of the first sentence's checksum (after its `*`).
    fn checksum_at(&self, out: &[u8]) -> usize {
        out.iter().position(|b| *b == b'*').map_or(0, |i| i + 1)
    }
}
