//! TUM trajectory files (`timestamp tx ty tz qx qy qz qw`, one pose per line), the format
//! `evo` and the TUM RGB-D tools read: a reader for planar poses and a writer.
//!
//! Stamps are decimal seconds. Both directions convert between the decimal text and
//! integer nanoseconds digit by digit, never through `f64`, so a stamp such as
//! `1700000000.123456789` survives a round trip exactly (an `f64` holds only about 16
//! significant digits).

use crate::ros2::geometry_msgs::Quaternion;
use crate::trajectory::{StampedPose, Trajectory};
use ekf_core::Pose2;
use std::fs::File;
use std::io::{self, BufRead, BufReader, BufWriter, Write};
use std::path::Path;

/// Names of the eight columns of a TUM line, for error messages.
const COLUMNS: [&str; 8] = ["timestamp", "tx", "ty", "tz", "qx", "qy", "qz", "qw"];

/// What a stamp must look like, for error messages.
const STAMP_EXPECTED: &str =
    "non-negative decimal seconds below 1.8e10 (e.g. 1700000000.123456789 or 1.7e9)";

/// What a coordinate must look like, for error messages.
const NUMBER_EXPECTED: &str = "a finite decimal number";

/// An error while reading or writing a TUM file. `label` names the file (usually its
/// path); `line` and `column` are 1-based.
#[derive(Debug, thiserror::Error)]
pub enum TumError {
    /// The file could not be opened, read or written.
    #[error("{label}: {source}")]
    Io {
        /// The file.
        label: String,
        /// The underlying error.
        #[source]
        source: io::Error,
    },
    /// A line does not have the eight fields of a TUM pose.
    #[error(
        "{label}:{line}: expected 8 whitespace-separated fields \
         (timestamp tx ty tz qx qy qz qw), found {found}"
    )]
    FieldCount {
        /// The file.
        label: String,
        /// Line number.
        line: usize,
        /// Number of fields on the line.
        found: usize,
    },
    /// A field is not a valid value for its column.
    #[error("{label}:{line}: column {column} ({field}) is {text:?}, expected {expected}")]
    Field {
        /// The file.
        label: String,
        /// Line number.
        line: usize,
        /// Column number (1 = timestamp … 8 = qw).
        column: usize,
        /// Name of the column.
        field: &'static str,
        /// The offending text.
        text: String,
        /// What the column must hold.
        expected: &'static str,
    },
    /// The orientation `(qx, qy, qz, qw)` is the zero quaternion, which has no heading.
    #[error(
        "{label}:{line}: columns 5-8 (qx qy qz qw) are zero or nearly so (norm at most 1e-6), \
         expected a unit quaternion"
    )]
    ZeroQuaternion {
        /// The file.
        label: String,
        /// Line number.
        line: usize,
    },
}

/// Reads a TUM trajectory from `reader`; `label` names the source in errors.
///
/// Lines that are empty or whose first non-blank character is `#` are skipped; fields are
/// separated by any run of spaces or tabs (`evo` itself wants single spaces); a UTF-8
/// byte-order mark is ignored. The stamp is converted to nanoseconds exactly from its
/// decimal text (an exponent such as numpy's `1.700000000123456789e+09` is accepted;
/// digits below 1 ns are rounded half up). The heading is the yaw of the quaternion,
///
/// `θ = atan2(2(qw·qz + qx·qy), qw² + qx² − qy² − qz²)`,
///
/// which for a unit quaternion is `atan2(2(qw·qz + qx·qy), 1 − 2(qy² + qz²))` and is
/// also right for a quaternion that is not normalised. `tz`, roll and pitch are
/// dropped: the pose is projected onto the plane. An empty input gives an empty
/// trajectory.
pub fn read_tum<R: BufRead>(reader: R, label: &str) -> Result<Trajectory, TumError> {
    let mut trajectory = Trajectory::new();
    for (index, line) in reader.lines().enumerate() {
        let line = line.map_err(|source| TumError::Io {
            label: label.to_owned(),
            source,
        })?;
        let text = if index == 0 {
            line.trim_start_matches('\u{feff}')
        } else {
            &line
        };
        let text = text.trim();
        if text.is_empty() || text.starts_with('#') {
            continue;
        }
        let (t_ns, pose) = parse_line(text, label, index + 1)?;
        trajectory.push(t_ns, pose);
    }
    Ok(trajectory)
}

/// Reads the TUM file at `path` (see [`read_tum`]); errors name the path.
pub fn read_tum_file(path: &Path) -> Result<Trajectory, TumError> {
    let label = path.display().to_string();
    let file = File::open(path).map_err(|source| TumError::Io {
        label: label.clone(),
        source,
    })?;
    read_tum(BufReader::new(file), &label)
}

/// Writes `trajectory` in TUM format: a `#` header line, then per pose
/// `t tx ty 0 0 0 qz qw` with `qz = sin(θ/2)`, `qw = cos(θ/2)`.
///
/// The stamp is printed from the integer nanoseconds with exactly nine decimals
/// (`1700000000.000000001`); coordinates use the shortest decimal text that reads back
/// to the same `f64`.
pub fn write_tum<W: Write>(mut writer: W, trajectory: &Trajectory) -> io::Result<()> {
    write_tum_header(&mut writer)?;
    for sample in trajectory {
        write_tum_row(&mut writer, sample)?;
    }
    writer.flush()
}

/// Writes the TUM header comment line, for a writer that streams rows.
pub fn write_tum_header<W: Write>(mut writer: W) -> io::Result<()> {
    writeln!(writer, "# timestamp tx ty tz qx qy qz qw")
}

/// Writes one TUM row (`t x y z qx qy qz qw`, planar: z = qx = qy = 0).
pub fn write_tum_row<W: Write>(mut writer: W, sample: &StampedPose) -> io::Result<()> {
    let (qz, qw) = (0.5 * sample.pose.theta).sin_cos();
    writeln!(
        writer,
        "{} {} {} 0 0 0 {} {}",
        format_stamp(sample.t_ns),
        sample.pose.x,
        sample.pose.y,
        qz,
        qw
    )
}

/// Writes `trajectory` to the file at `path` (created or truncated; see [`write_tum`]).
pub fn write_tum_file(path: &Path, trajectory: &Trajectory) -> Result<(), TumError> {
    let io_error = |source| TumError::Io {
        label: path.display().to_string(),
        source,
    };
    let file = File::create(path).map_err(io_error)?;
    write_tum(BufWriter::new(file), trajectory).map_err(io_error)
}

/// `t_ns` as decimal seconds with nine decimals, from the integer (no rounding).
fn format_stamp(t_ns: u64) -> String {
    format!("{}.{:09}", t_ns / 1_000_000_000, t_ns % 1_000_000_000)
}

/// Parses one non-comment line into a stamp and a planar pose.
fn parse_line(text: &str, label: &str, line: usize) -> Result<(u64, Pose2<f64>), TumError> {
    let fields: Vec<&str> = text.split_whitespace().collect();
    if fields.len() != COLUMNS.len() {
        return Err(TumError::FieldCount {
            label: label.to_owned(),
            line,
            found: fields.len(),
        });
    }
    let field_error = |column: usize, expected: &'static str| TumError::Field {
        label: label.to_owned(),
        line,
        column: column + 1,
        field: COLUMNS[column],
        text: fields[column].to_owned(),
        expected,
    };
    let t_ns = parse_stamp_ns(fields[0]).ok_or_else(|| field_error(0, STAMP_EXPECTED))?;
    let mut values = [0.0_f64; 7];
    for (column, value) in values.iter_mut().enumerate() {
        *value = fields[column + 1]
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| field_error(column + 1, NUMBER_EXPECTED))?;
    }
    let [x, y, _z, qx, qy, qz, qw] = values;
    let yaw = Quaternion {
        x: qx,
        y: qy,
        z: qz,
        w: qw,
    }
    .yaw();
    // The components are finite, so only a (near) zero quaternion has no yaw.
    if !yaw.is_finite() {
        return Err(TumError::ZeroQuaternion {
            label: label.to_owned(),
            line,
        });
    }
    Ok((t_ns, Pose2::new(x, y, yaw)))
}

/// Decimal seconds (`[+]digits[.digits][(e|E)[±]digits]`) to nanoseconds, exactly, with
/// sub-nanosecond digits rounded half up. `None` if the text is not such a number, has
/// more than 38 significant digits, or does not fit a `u64`.
fn parse_stamp_ns(text: &str) -> Option<u64> {
    let (mantissa, exponent) = match text.find(['e', 'E']) {
        Some(i) => (&text[..i], text[i + 1..].parse::<i32>().ok()?),
        None => (text, 0),
    };
    let mantissa = mantissa.strip_prefix('+').unwrap_or(mantissa);
    let (int, frac) = mantissa.split_once('.').unwrap_or((mantissa, ""));
    if int.is_empty() && frac.is_empty() {
        return None;
    }
    if !int.bytes().chain(frac.bytes()).all(|b| b.is_ascii_digit()) {
        return None;
    }
    // Trailing zeros of the fraction do not change the value; dropping them keeps long
    // zero-padded stamps within the 38 digits a u128 holds.
    let frac = frac.trim_end_matches('0');
    let mut digits: u128 = 0;
    for b in int.bytes().chain(frac.bytes()) {
        digits = digits.checked_mul(10)?.checked_add(u128::from(b - b'0'))?;
    }
    // value = digits · 10^(exponent − |frac|) s = digits · 10^(shift) ns
    let shift = i64::from(exponent) - frac.len() as i64 + 9;
    let ns = if shift >= 0 {
        digits.checked_mul(10_u128.checked_pow(u32::try_from(shift).ok()?)?)?
    } else {
        match 10_u128.checked_pow(u32::try_from(-shift).ok()?) {
            // digits < 2^128 < 10^39 ≤ divisor: the value is below 0.35 ns.
            None => 0,
            Some(divisor) => {
                let (q, r) = (digits / divisor, digits % divisor);
                if r >= divisor - r {
                    q + 1
                } else {
                    q
                }
            }
        }
    };
    u64::try_from(ns).ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stamps_parse_exactly() {
        assert_eq!(parse_stamp_ns("0"), Some(0));
        assert_eq!(
            parse_stamp_ns("1700000000.123456789"),
            Some(1_700_000_000_123_456_789)
        );
        assert_eq!(parse_stamp_ns("1.5"), Some(1_500_000_000));
        assert_eq!(parse_stamp_ns(".5"), Some(500_000_000));
        assert_eq!(parse_stamp_ns("2."), Some(2_000_000_000));
        assert_eq!(parse_stamp_ns("+3"), Some(3_000_000_000));
        assert_eq!(
            parse_stamp_ns("1.700000000123456789e+09"),
            Some(1_700_000_000_123_456_789)
        );
        assert_eq!(parse_stamp_ns("17E-1"), Some(1_700_000_000));
        assert_eq!(
            parse_stamp_ns("1.0000000000000000000000000000000000000000000000"),
            Some(1_000_000_000)
        );
    }

    #[test]
    fn sub_nanosecond_digits_round_half_up() {
        assert_eq!(parse_stamp_ns("0.0000000014"), Some(1));
        assert_eq!(parse_stamp_ns("0.0000000015"), Some(2));
        assert_eq!(parse_stamp_ns("1e-60"), Some(0));
    }

    #[test]
    fn bad_stamps_are_rejected() {
        for text in [
            "", ".", "-1", "1.2.3", "1e", "abc", "1e30", "nan", "1,5", "0x10",
        ] {
            assert_eq!(parse_stamp_ns(text), None, "{text:?}");
        }
    }

    #[test]
    fn stamps_format_from_integer() {
        assert_eq!(format_stamp(0), "0.000000000");
        assert_eq!(
            format_stamp(1_700_000_000_000_000_001),
            "1700000000.000000001"
        );
        assert_eq!(format_stamp(u64::MAX), "18446744073.709551615");
    }
}
