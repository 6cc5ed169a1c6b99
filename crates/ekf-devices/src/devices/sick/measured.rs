//! Measured values (`B0` replies): the count word with its unit bits, the 16-bit values
//! (low 13 bits = range), and their conversion to a ROS `LaserScan` in metres.

use super::telegram::Variant;

/// Unit of the range values, bits 14–15 of the count word.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RangeUnit {
    /// `00`: centimetres (the 80 m mode).
    Centimetres,
    /// `01`: millimetres (the 8 m mode).
    Millimetres,
}

impl RangeUnit {
    /// Metres per count.
    pub fn metres(self) -> f64 {
        match self {
            RangeUnit::Centimetres => 0.01,
            RangeUnit::Millimetres => 0.001,
        }
    }

    fn bits(self) -> u16 {
        match self {
            RangeUnit::Centimetres => 0,
            RangeUnit::Millimetres => 1 << 14,
        }
    }
}

/// Mask of the range in a value (8/80 m modes); bits 13–15 are flags.
pub const RANGE_MASK: u16 = 0x1fff;
/// Smallest range value that is an error code, not a distance (8183 = 0x1FF7 up to
/// 8191 = 0x1FFF: no echo, dazzled, …).
pub const FIRST_ERROR_CODE: u16 = 0x1ff7;
/// The error code for no echo within the measurable span (0x1FFF).
pub const NO_ECHO: u16 = RANGE_MASK;

/// Why a `B0` payload could not be decoded; offsets count from the first data byte
/// after CMD.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MeasuredError {
    /// Fewer than two bytes: no count word.
    #[error("B0 telegram has {0} data bytes, expected at least 2 (the count word)")]
    NoCountWord(usize),
    /// Units `10` or `11` are reserved.
    #[error("B0 count word {word:04x} at byte offset 0: unit bits 14-15 are {bits:02b}, expected 00 (cm) or 01 (mm)")]
    ReservedUnit {
        /// The count word.
        word: u16,
        /// Bits 14–15.
        bits: u16,
    },
    /// The count says more values than the telegram holds.
    #[error("B0 count word says {count} values ({} bytes from byte offset 2) but only {available} bytes follow", 2 * count)]
    ShortData {
        /// Values announced.
        count: usize,
        /// Data bytes after the count word.
        available: usize,
    },
    /// The number of values does not fit the configured angle and resolution.
    #[error("B0 telegram has {count} values, expected {expected} for {angle}° at {res}°")]
    WrongCount {
        /// Values received.
        count: usize,
        /// Values the variant has.
        expected: usize,
        /// Scanning angle (°).
        angle: u16,
        /// Resolution (°).
        res: f64,
    },
}

/// One scan's values as the scanner sent them.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MeasuredValues {
    /// Unit of the ranges.
    pub unit: RangeUnit,
    /// The raw 16-bit values, first beam (the scanner's right) first.
    pub values: Vec<u16>,
}

impl MeasuredValues {
    /// Decodes a `B0` reply's payload (data without the STATUS byte).
    pub fn decode(payload: &[u8]) -> Result<Self, MeasuredError> {
        let [c0, c1, rest @ ..] = payload else {
            return Err(MeasuredError::NoCountWord(payload.len()));
        };
        let word = u16::from_le_bytes([*c0, *c1]);
        let unit = match word >> 14 {
            0 => RangeUnit::Centimetres,
            1 => RangeUnit::Millimetres,
            bits => return Err(MeasuredError::ReservedUnit { word, bits }),
        };
        let count = usize::from(word & 0x3ff);
        if rest.len() < 2 * count {
            return Err(MeasuredError::ShortData {
                count,
                available: rest.len(),
            });
        }
        let values = rest[..2 * count]
            .chunks_exact(2)
            .map(|b| u16::from_le_bytes([b[0], b[1]]))
            .collect();
        Ok(Self { unit, values })
    }

    /// The payload of a `B0` reply (without STATUS): count word, then the values.
    pub fn encode(&self) -> Vec<u8> {
        let word = (self.values.len() as u16 & 0x3ff) | self.unit.bits();
        let mut out = word.to_le_bytes().to_vec();
        for v in &self.values {
            out.extend_from_slice(&v.to_le_bytes());
        }
        out
    }

    /// Ranges in metres as REP-117 asks: no echo ([`NO_ECHO`]) and zero become +∞ (no
    /// return in range), the other error codes (dazzle, …) NaN (an erroneous reading).
    pub fn ranges(&self) -> Vec<f32> {
        let metres = self.unit.metres();
        self.values
            .iter()
            .map(|v| match v & RANGE_MASK {
                0 | NO_ECHO => f32::INFINITY,
                r if r >= FIRST_ERROR_CODE => f32::NAN,
                r => (f64::from(r) * metres) as f32,
            })
            .collect()
    }

    /// The raw value for a range in metres (rounded to the unit): +∞ and ranges beyond
    /// the measurable span give the no-echo code [`NO_ECHO`], NaN (an error return, as
    /// the simulator writes it) the first error code [`FIRST_ERROR_CODE`].
    pub fn value_of(range: f64, unit: RangeUnit) -> u16 {
        if range.is_nan() {
            return FIRST_ERROR_CODE;
        }
        let counts = (range / unit.metres()).round();
        if counts.is_finite() && counts >= 1.0 && counts < f64::from(FIRST_ERROR_CODE) {
            counts as u16
        } else {
            NO_ECHO
        }
    }

    /// Checks the number of values against the configured variant.
    pub fn check_count(&self, variant: Variant) -> Result<(), MeasuredError> {
        let expected = variant.values();
        if self.values.len() == expected {
            Ok(())
        } else {
            Err(MeasuredError::WrongCount {
                count: self.values.len(),
                expected,
                angle: variant.angle_deg,
                res: f64::from(variant.resolution_cdeg) / 100.0,
            })
        }
    }
}

/// The scan geometry of a variant in the laser frame (x forward, counter-clockwise, as
/// ROS SICK drivers publish it): the first beam at −angle/2, the scanner's right.
pub fn scan_angles(variant: Variant) -> (f32, f32, f32) {
    let half = (f64::from(variant.angle_deg) / 2.0).to_radians();
    let step = (f64::from(variant.resolution_cdeg) / 100.0).to_radians();
    (-half as f32, half as f32, step as f32)
}

/// The largest range a unit can express (m): 8.182 m in mm, 81.82 m in cm.
pub fn range_max(unit: RangeUnit) -> f32 {
    (f64::from(FIRST_ERROR_CODE - 1) * unit.metres()) as f32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decode_units_and_error_codes() {
        // 3 values in mm: 1234 mm, an error code (dazzle, 8190), 0; flag bits 13-15 set
        // on the first value must not change its range.
        let payload = [
            0x03, 0x40, 0xd2, 0xe4, 0xfe, 0x1f, 0x00, 0x00, 0x99, /* extra byte ignored */
        ];
        let m = MeasuredValues::decode(&payload).unwrap();
        assert_eq!(m.unit, RangeUnit::Millimetres);
        let r = m.ranges();
        assert!((r[0] - 1.234).abs() < 1e-6, "{r:?}");
        // REP-117: an error return is NaN, no return +∞.
        assert!(r[1].is_nan() && r[2].is_infinite());
        assert!(MeasuredValues::decode(&[0x01, 0x40, 0xff, 0x1f])
            .unwrap()
            .ranges()[0]
            .is_infinite());
        let cm = MeasuredValues::decode(&[0x01, 0x00, 0xe8, 0x03]).unwrap();
        assert_eq!(cm.unit, RangeUnit::Centimetres);
        assert!((cm.ranges()[0] - 10.0).abs() < 1e-6);
    }

    #[test]
    fn decode_errors_name_what_was_expected() {
        assert_eq!(
            MeasuredValues::decode(&[0x05]),
            Err(MeasuredError::NoCountWord(1))
        );
        let e = MeasuredValues::decode(&[0x01, 0x80, 0, 0]).unwrap_err();
        assert!(e.to_string().contains("unit bits 14-15 are 10"), "{e}");
        let e = MeasuredValues::decode(&[0x03, 0x40, 0, 0]).unwrap_err();
        assert_eq!(
            e.to_string(),
            "B0 count word says 3 values (6 bytes from byte offset 2) but only 2 bytes follow"
        );
    }

    #[test]
    fn encode_round_trips() {
        let ranges = [0.5, 7.999, f64::INFINITY, 100.0, f64::NAN];
        let m = MeasuredValues {
            unit: RangeUnit::Millimetres,
            values: ranges
                .iter()
                .map(|&r| MeasuredValues::value_of(r, RangeUnit::Millimetres))
                .collect(),
        };
        let back = MeasuredValues::decode(&m.encode()).unwrap();
        assert_eq!(back, m);
        let r = back.ranges();
        assert!((r[0] - 0.5).abs() < 1e-6 && (r[1] - 7.999).abs() < 1e-6);
        assert!(r[2].is_infinite() && r[3].is_infinite() && r[4].is_nan());
        assert!(m.check_count(Variant::DEFAULT).is_err());
        let (min, max, step) = scan_angles(Variant::DEFAULT);
        assert!((f64::from(min) + std::f64::consts::FRAC_PI_2).abs() < 1e-6);
        assert!((f64::from(max) - std::f64::consts::FRAC_PI_2).abs() < 1e-6);
        assert!((f64::from(step) - 0.5f64.to_radians()).abs() < 1e-9);
    }
}
