//! Range checks for configuration values, shared by every crate that owns a section of
//! the configuration (docs/ARCHITECTURE.md §1): each section checks its own keys with
//! these, and the crate that reads the file adds the table the section sits in and the
//! line.
//!
//! No allocation: keys are static dotted paths (`robot.wheel_radius`), the bound is in
//! the [`Expected`] value, and the message is written when the error is displayed.

use core::fmt;

/// What a configuration value must be.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Expected {
    /// A finite number `> 0`.
    Positive,
    /// A probability in the open interval `(0, 1)`.
    Probability,
    /// A length in `(0, max]` metres: a larger one is a unit slip (millimetres).
    LengthUpTo(f64),
    /// A coordinate or offset within `±max` metres.
    MetresWithin(f64),
    /// An angle within `±2π` radians: a larger one is in degrees.
    Radians,
    /// A time in `[min, max]` seconds.
    SecondsIn(f64, f64),
    /// A length in `[min, max]` metres.
    MetresIn(f64, f64),
    /// Degrees within `±max`, with the reason for the bound.
    DegreesWithin(f64, &'static str),
}

impl Expected {
    /// Whether `v` is what is expected.
    pub fn holds(self, v: f64) -> bool {
        match self {
            Expected::Positive => v.is_finite() && v > 0.0,
            Expected::Probability => v > 0.0 && v < 1.0,
            Expected::LengthUpTo(max) => v.is_finite() && v > 0.0 && v <= max,
            Expected::MetresWithin(max) => v.is_finite() && v.abs() <= max,
            Expected::Radians => v.is_finite() && v.abs() <= core::f64::consts::TAU,
            Expected::SecondsIn(min, max) | Expected::MetresIn(min, max) => {
                v.is_finite() && (min..=max).contains(&v)
            }
            Expected::DegreesWithin(max, _) => v.is_finite() && v.abs() <= max,
        }
    }
}

/// A configuration value that is not what its key needs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InvalidSetting {
    /// The table the key sits in, dotted (`localizer`); empty when the key is given from
    /// the section's own root.
    pub table: &'static str,
    /// The key, dotted from the table (`robot.wheel_radius`).
    pub key: &'static str,
    /// The value found.
    pub found: f64,
    /// What was expected.
    pub expected: Expected,
}

impl InvalidSetting {
    /// The same error for a section that sits in `table` of the file.
    pub fn in_table(self, table: &'static str) -> Self {
        Self { table, ..self }
    }

    /// The key with its table, as the file spells it (`localizer.robot.wheel_radius`).
    pub fn full_key(&self) -> FullKey<'_> {
        FullKey(self)
    }

    /// What was expected and what was found, without the key:
    /// `expected a finite number > 0, found -0.05`.
    pub fn message(&self) -> Message<'_> {
        Message(self)
    }
}

/// Checks that `found` is `expected`, naming `key` if not.
pub fn check(key: &'static str, found: f64, expected: Expected) -> Result<(), InvalidSetting> {
    if expected.holds(found) {
        Ok(())
    } else {
        Err(InvalidSetting {
            table: "",
            key,
            found,
            expected,
        })
    }
}

/// Displays an [`InvalidSetting`]'s dotted key with its table.
pub struct FullKey<'a>(&'a InvalidSetting);

impl fmt::Display for FullKey<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.0.table {
            "" => f.write_str(self.0.key),
            table => write!(f, "{table}.{}", self.0.key),
        }
    }
}

/// Displays an [`InvalidSetting`]'s expectation and the value found.
pub struct Message<'a>(&'a InvalidSetting);

impl fmt::Display for Message<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let found = Number(self.0.found);
        match self.0.expected {
            Expected::Positive => write!(f, "expected a finite number > 0, found {found}"),
            Expected::Probability => write!(f, "expected a probability in (0, 1), found {found}"),
            Expected::LengthUpTo(max) => write!(
                f,
                "expected metres in (0, {}], found {found} (millimetres?)",
                Number(max)
            ),
            Expected::MetresWithin(max) => {
                write!(f, "expected metres within ±{}, found {found}", Number(max))
            }
            Expected::Radians => write!(
                f,
                "expected radians within ±2π (6.283), found {found} (degrees?)"
            ),
            Expected::SecondsIn(min, max) => write!(
                f,
                "expected seconds in [{}, {}], found {found}",
                Number(min),
                Number(max)
            ),
            Expected::MetresIn(min, max) => write!(
                f,
                "expected metres in [{}, {}], found {found}",
                Number(min),
                Number(max)
            ),
            Expected::DegreesWithin(max, why) => write!(
                f,
                "expected degrees within ±{}{}, found {found}",
                Number(max),
                why
            ),
        }
    }
}

impl fmt::Display for InvalidSetting {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.full_key(), self.message())
    }
}

#[cfg(feature = "std")]
impl std::error::Error for InvalidSetting {}

/// A number as a person writes it in a config file: plain, or in exponent form when very
/// large or very small (`1e300`, not 301 digits).
struct Number(f64);

impl fmt::Display for Number {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let v = self.0;
        if v != 0.0 && v.is_finite() && !(1e-4..1e6).contains(&v.abs()) {
            write!(f, "{v:e}")
        } else {
            write!(f, "{v}")
        }
    }
}

#[cfg(all(test, feature = "std"))]
mod tests {
    use super::*;

    #[test]
    fn each_expectation_accepts_its_range_and_names_what_it_refuses() {
        let cases = [
            (
                Expected::Positive,
                0.05,
                -0.05,
                "expected a finite number > 0, found -0.05",
            ),
            (
                Expected::Positive,
                1.0,
                f64::INFINITY,
                "expected a finite number > 0, found inf",
            ),
            (
                Expected::Probability,
                0.99,
                1.0,
                "expected a probability in (0, 1), found 1",
            ),
            (
                Expected::Probability,
                0.5,
                f64::NAN,
                "expected a probability in (0, 1), found NaN",
            ),
            (
                Expected::LengthUpTo(2.0),
                2.0,
                1e300,
                "expected metres in (0, 2], found 1e300 (millimetres?)",
            ),
            (
                Expected::MetresWithin(1e7),
                -1e7,
                -2e7,
                "expected metres within ±1e7, found -2e7",
            ),
            (
                Expected::Radians,
                -6.0,
                90.0,
                "expected radians within ±2π (6.283), found 90 (degrees?)",
            ),
            (
                Expected::SecondsIn(0.0, 60.0),
                0.0,
                61.0,
                "expected seconds in [0, 60], found 61",
            ),
            (
                Expected::MetresIn(0.05, 10.0),
                0.3,
                0.001,
                "expected metres in [0.05, 10], found 0.001",
            ),
            (
                Expected::DegreesWithin(89.0, " (the poles)"),
                -89.0,
                100.5,
                "expected degrees within ±89 (the poles), found 100.5",
            ),
        ];
        for (expected, good, bad, message) in cases {
            assert_eq!(check("k", good, expected), Ok(()), "{expected:?} {good}");
            let err = check("k", bad, expected).unwrap_err();
            assert_eq!(err.message().to_string(), message);
        }
    }

    #[test]
    fn the_key_carries_the_table_it_sits_in() {
        let err = check("robot.track", 0.0, Expected::Positive).unwrap_err();
        assert_eq!(
            err.to_string(),
            "robot.track: expected a finite number > 0, found 0"
        );
        let err = err.in_table("localizer");
        assert_eq!(err.full_key().to_string(), "localizer.robot.track");
        assert_eq!(
            err.to_string(),
            "localizer.robot.track: expected a finite number > 0, found 0"
        );
    }
}
