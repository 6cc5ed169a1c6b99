//! Reading typed values out of one whitespace-separated log line, with errors that name
//! the line, the record and the field.

use super::error::ImportError;
use ekf_core::Pose2;

/// Longest found text quoted in an error.
const QUOTE_MAX: usize = 40;

/// The fields of one line; field 1 is the record tag.
pub(crate) struct Fields<'a> {
    line: u64,
    words: Vec<&'a str>,
}

impl<'a> Fields<'a> {
    /// Splits `text` (line number `line`) at whitespace.
    pub(crate) fn new(line: u64, text: &'a str) -> Self {
        Self {
            line,
            words: text.split_whitespace().collect(),
        }
    }

    /// The record tag (field 1), if the line is not blank.
    pub(crate) fn tag(&self) -> Option<&'a str> {
        self.words.first().copied()
    }

    /// Number of fields, the tag included.
    pub(crate) fn len(&self) -> usize {
        self.words.len()
    }

    /// The text of 1-based field `field`.
    pub(crate) fn text(&self, field: usize) -> Option<&'a str> {
        field
            .checked_sub(1)
            .and_then(|i| self.words.get(i))
            .copied()
    }

    fn tag_or_empty(&self) -> String {
        self.tag().unwrap_or("").to_owned()
    }

    /// Fails unless the line has exactly `expected` fields (a fixed layout).
    pub(crate) fn expect_len(&self, expected: usize) -> Result<(), ImportError> {
        self.check_len(expected, None)
    }

    /// Fails unless the line has exactly `expected` fields, as a count in it (`context`,
    /// e.g. `declares 180 readings`) says.
    pub(crate) fn expect_declared_len(
        &self,
        expected: usize,
        context: &str,
    ) -> Result<(), ImportError> {
        self.check_len(expected, Some(context))
    }

    fn check_len(&self, expected: usize, context: Option<&str>) -> Result<(), ImportError> {
        if self.len() == expected {
            Ok(())
        } else {
            Err(self.count_error(expected, context))
        }
    }

    /// The error for a line with `self.len()` fields where `expected` are needed.
    pub(crate) fn count_error(&self, expected: usize, context: Option<&str>) -> ImportError {
        ImportError::FieldCount {
            line: self.line,
            record: self.tag_or_empty(),
            context: context.map(str::to_owned),
            expected,
            found: self.len(),
        }
    }

    /// The error for field `field` (`name`) not being `expected`.
    pub(crate) fn bad(
        &self,
        field: usize,
        name: &'static str,
        expected: &'static str,
    ) -> ImportError {
        let found: String = self
            .text(field)
            .unwrap_or("<missing>")
            .chars()
            .take(QUOTE_MAX)
            .collect();
        ImportError::BadField {
            line: self.line,
            record: self.tag_or_empty(),
            field,
            name,
            expected,
            found,
        }
    }

    /// Field `field` as a finite `f64`.
    pub(crate) fn f64(&self, field: usize, name: &'static str) -> Result<f64, ImportError> {
        self.text(field)
            .and_then(|t| t.parse::<f64>().ok())
            .filter(|v| v.is_finite())
            .ok_or_else(|| self.bad(field, name, "a finite number"))
    }

    /// Field `field` as a finite `f32` (a range reading).
    pub(crate) fn f32(&self, field: usize, name: &'static str) -> Result<f32, ImportError> {
        self.text(field)
            .and_then(|t| t.parse::<f32>().ok())
            .filter(|v| v.is_finite())
            .ok_or_else(|| self.bad(field, name, "a finite number"))
    }

    /// Field `field` as a count (non-negative integer).
    pub(crate) fn count(&self, field: usize, name: &'static str) -> Result<usize, ImportError> {
        self.text(field)
            .and_then(|t| t.parse::<usize>().ok())
            .ok_or_else(|| self.bad(field, name, "a non-negative integer"))
    }

    /// Fields `first`, `first + 1`, `first + 2` as a pose `(x, y, θ)`; θ is wrapped.
    pub(crate) fn pose(
        &self,
        first: usize,
        names: [&'static str; 3],
    ) -> Result<Pose2<f64>, ImportError> {
        Ok(Pose2::new(
            self.f64(first, names[0])?,
            self.f64(first + 1, names[1])?,
            self.f64(first + 2, names[2])?,
        ))
    }

    /// `count` range readings starting at field `first`.
    pub(crate) fn ranges(&self, first: usize, count: usize) -> Result<Vec<f32>, ImportError> {
        (first..first + count)
            .map(|f| self.f32(f, "range"))
            .collect()
    }

    /// Field `field` as a timestamp in seconds, possibly one that needs repair.
    pub(crate) fn stamp(&self, field: usize, name: &'static str) -> Result<RawStamp, ImportError> {
        self.text(field)
            .and_then(RawStamp::parse)
            .ok_or_else(|| self.bad(field, name, "a time in seconds"))
    }

    /// The 1-based line number.
    pub(crate) fn line(&self) -> u64 {
        self.line
    }

    /// Field `field` as a time in seconds, converted to nanoseconds.
    pub(crate) fn time_ns(&self, field: usize, name: &'static str) -> Result<u64, ImportError> {
        self.text(field)
            .and_then(seconds_to_ns)
            .ok_or_else(|| self.bad(field, name, "a non-negative time in seconds"))
    }
}

/// Parses a non-negative time in seconds to nanoseconds. Plain decimals (`1137834225.713386`)
/// are converted digit by digit, so no precision is lost; digits past the nanosecond are
/// dropped. Other forms that Rust reads as a number (`1.5e3`) go through `f64`.
pub(crate) fn seconds_to_ns(text: &str) -> Option<u64> {
    let (int, frac) = text.split_once('.').unwrap_or((text, ""));
    let is_digits = |s: &str| s.bytes().all(|b| b.is_ascii_digit());
    if is_digits(int) && is_digits(frac) && !(int.is_empty() && frac.is_empty()) {
        let secs: u64 = if int.is_empty() { 0 } else { int.parse().ok()? };
        let mut nanos: u64 = 0;
        for i in 0..9 {
            let digit = frac.as_bytes().get(i).map_or(0, |b| u64::from(b - b'0'));
            nanos = nanos * 10 + digit;
        }
        return secs.checked_mul(1_000_000_000)?.checked_add(nanos);
    }
    let secs: f64 = text.parse().ok()?;
    let ns = (secs * 1e9).round();
    // u64::MAX as f64 rounds up to 2^64, so `<` keeps the cast in range.
    (secs.is_finite() && ns >= 0.0 && ns < u64::MAX as f64).then_some(ns as u64)
}

/// A timestamp as read from the text, before repair.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum RawStamp {
    /// A positive time (ns).
    Valid(u64),
    /// Exactly zero.
    Zero,
    /// Not zero, but below one nanosecond in magnitude (uninitialised memory, e.g.
    /// `8.97e-67`).
    Denormal,
    /// Negative.
    Negative,
}

impl RawStamp {
    /// Reads a time in seconds; `None` if the text is not a finite number or does not fit
    /// in `u64` nanoseconds.
    pub(crate) fn parse(text: &str) -> Option<Self> {
        if let Some(ns) = seconds_to_ns(text) {
            if ns > 0 {
                return Some(Self::Valid(ns));
            }
        }
        let secs: f64 = text.parse().ok().filter(|s: &f64| s.is_finite())?;
        if secs == 0.0 {
            Some(Self::Zero)
        } else if secs.abs() < 1e-9 {
            Some(Self::Denormal)
        } else if secs < 0.0 {
            Some(Self::Negative)
        } else {
            None
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decimal_seconds_convert_exactly() {
        assert_eq!(
            seconds_to_ns("1137834225.713386"),
            Some(1_137_834_225_713_386_000)
        );
        assert_eq!(seconds_to_ns("21.0199"), Some(21_019_900_000));
        assert_eq!(seconds_to_ns("0"), Some(0));
        assert_eq!(seconds_to_ns(".5"), Some(500_000_000));
        assert_eq!(seconds_to_ns("7."), Some(7_000_000_000));
        assert_eq!(seconds_to_ns("1.0000000019"), Some(1_000_000_001));
        assert_eq!(seconds_to_ns("1.5e3"), Some(1_500_000_000_000));
    }

    #[test]
    fn invalid_times_are_rejected() {
        for bad in [
            "",
            ".",
            "-1",
            "abc",
            "nan",
            "inf",
            "1e30",
            "99999999999999999999",
        ] {
            assert_eq!(seconds_to_ns(bad), None, "{bad}");
        }
    }

    #[test]
    fn errors_name_line_record_and_field() {
        let f = Fields::new(1234, "FLASER 2 1.0 abc");
        let e = f.f64(4, "range").unwrap_err().to_string();
        assert_eq!(
            e,
            "line 1234: FLASER field 4 (range): expected a finite number, found 'abc'"
        );
        let e = f.f64(9, "x").unwrap_err().to_string();
        assert!(e.contains("found '<missing>'"), "{e}");
    }
}
