//! The JSON line-map file format (`docs/map-format.md`): writing, and loading with errors
//! that name the offending entry.
//!
//! Loading parses into a `serde_json::Value` and walks it by hand rather than deriving
//! `Deserialize`, so every error carries the path of the entry (`segments[2].end`) and
//! says what was expected there.

use super::json_path::{offset_of, path_at};
use super::{LineMap, MapSegment};
use alloc::borrow::ToOwned;
use alloc::format;
use alloc::string::{String, ToString};
use alloc::vec::Vec;
use core::fmt::{self, Write};
use nalgebra::Point2;
use serde_json::{Map, Value};

/// The value of the file's `"format"` member.
pub const MAP_FORMAT: &str = "ekf-loc line map";
/// The file format version this crate reads and writes.
pub const MAP_FORMAT_VERSION: u64 = 1;

/// Why a map file was refused: where (`path`, e.g. `segments[2].end`, empty for the whole
/// document) and what was wrong.
#[derive(Debug, Clone, PartialEq)]
pub struct MapFormatError {
    /// JSON path of the offending entry: member names joined by `.`, array indices in
    /// brackets. Empty for the document itself.
    pub path: String,
    /// Index into `segments` of the offending segment, if the error is inside one.
    pub segment: Option<usize>,
    /// What was wrong.
    pub kind: MapFormatErrorKind,
}

/// What was wrong with a map file.
#[derive(Debug, Clone, PartialEq)]
pub enum MapFormatErrorKind {
    /// The text is not JSON (this includes `NaN` and out-of-range numbers, which JSON
    /// cannot hold).
    Syntax {
        /// 1-based line of the error.
        line: usize,
        /// Column of the error as serde_json reports it (1-based).
        column: usize,
        /// The parser's message.
        message: String,
    },
    /// A required member is absent.
    MissingField {
        /// The member's name.
        field: &'static str,
    },
    /// A member this format does not define (a typo, or a newer version's field).
    UnknownField {
        /// The member's name.
        field: String,
    },
    /// A value of the wrong kind.
    WrongValue {
        /// What was expected, e.g. "an array [x, y] of two finite numbers".
        expected: &'static str,
        /// What was found, shortened.
        found: String,
    },
    /// A segment whose end points coincide (or that has no line through it).
    ZeroLength,
    /// A coordinate that is not a finite number (only when saving).
    NonFinite,
}

impl fmt::Display for MapFormatError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let at = if self.path.is_empty() {
            "map file"
        } else {
            self.path.as_str()
        };
        match &self.kind {
            MapFormatErrorKind::Syntax {
                line,
                column,
                message,
            } => write!(
                f,
                "{at}: invalid JSON at line {line}, column {column}: {message}"
            ),
            MapFormatErrorKind::MissingField { field } => {
                write!(f, "{at}: missing field `{field}`")
            }
            MapFormatErrorKind::UnknownField { field } => write!(
                f,
                "{at}: unknown field `{field}` (format version {MAP_FORMAT_VERSION})"
            ),
            MapFormatErrorKind::WrongValue { expected, found } => {
                write!(f, "{at}: expected {expected}, found {found}")
            }
            MapFormatErrorKind::ZeroLength => write!(
                f,
                "{at}: zero-length segment: fields `start` and `end` are the same point"
            ),
            MapFormatErrorKind::NonFinite => write!(f, "{at}: coordinate is not finite"),
        }
    }
}

#[cfg(feature = "std")]
impl std::error::Error for MapFormatError {}

impl MapFormatError {
    fn new(path: String, kind: MapFormatErrorKind) -> Self {
        let segment = segment_index(&path);
        Self {
            path,
            segment,
            kind,
        }
    }

    fn wrong(path: String, expected: &'static str, found: &Value) -> Self {
        Self::new(
            path,
            MapFormatErrorKind::WrongValue {
                expected,
                found: describe(found),
            },
        )
    }
}

/// The index `i` of a path that starts with `segments[i]`.
fn segment_index(path: &str) -> Option<usize> {
    let rest = path.strip_prefix("segments[")?;
    rest[..rest.find(']')?].parse().ok()
}

/// serde_json's message without its own " at line L column C" suffix.
fn parser_message(e: &serde_json::Error) -> String {
    let full = e.to_string();
    let suffix = format!(" at line {} column {}", e.line(), e.column());
    full.strip_suffix(suffix.as_str())
        .unwrap_or(&full)
        .to_owned()
}

/// A short description of a JSON value for error messages.
fn describe(value: &Value) -> String {
    let kind = match value {
        Value::Null => return "null".to_owned(),
        Value::Bool(b) => return b.to_string(),
        Value::Number(n) => return format!("the number {n}"),
        Value::String(s) if s.chars().count() <= 40 => return format!("the string {s:?}"),
        Value::String(_) => "a long string",
        Value::Array(a) => return format!("an array of {} elements", a.len()),
        Value::Object(_) => "an object",
    };
    kind.to_owned()
}

impl LineMap {
    /// Parses a map file (UTF-8 JSON text). See `docs/map-format.md`.
    pub fn from_json(text: &str) -> Result<Self, MapFormatError> {
        Self::from_json_bytes(text.as_bytes())
    }

    /// Parses a map file from bytes (must be UTF-8 JSON). Never panics; every error names
    /// the entry it is about.
    pub fn from_json_bytes(bytes: &[u8]) -> Result<Self, MapFormatError> {
        let value: Value = serde_json::from_slice(bytes).map_err(|e| {
            let path = path_at(bytes, offset_of(bytes, e.line(), e.column()));
            MapFormatError::new(
                path,
                MapFormatErrorKind::Syntax {
                    line: e.line(),
                    column: e.column(),
                    message: parser_message(&e),
                },
            )
        })?;
        from_value(&value)
    }

    /// Writes the map as a file of format version 1: one segment per line, numbers in
    /// the shortest form that reads back to the same `f64`, so `from_json(to_json(m))`
    /// reproduces every end point exactly. Fails (naming the segment) on a non-finite
    /// coordinate or a zero-length segment, which loading would refuse.
    pub fn to_json(&self) -> Result<String, MapFormatError> {
        let mut out = String::new();
        let frame_id = Value::String(self.frame_id.clone()).to_string();
        // Writing to a String cannot fail.
        let _ = write!(
            out,
            "{{\n  \"format\": \"{MAP_FORMAT}\",\n  \"version\": {MAP_FORMAT_VERSION},\n  \"frame_id\": {frame_id},\n  \"segments\": ["
        );
        for (i, s) in self.segments.iter().enumerate() {
            check_segment(i, s)?;
            let sep = if i == 0 { "" } else { "," };
            let _ = write!(
                out,
                "{sep}\n    {{\"start\": [{}, {}], \"end\": [{}, {}]}}",
                number(s.start.x),
                number(s.start.y),
                number(s.end.x),
                number(s.end.y),
            );
        }
        out.push_str(if self.segments.is_empty() {
            "]\n}\n"
        } else {
            "\n  ]\n}\n"
        });
        Ok(out)
    }
}

/// A finite `f64` as JSON, in the shortest form that parses back to the same value.
fn number(v: f64) -> String {
    Value::from(v).to_string()
}

fn check_segment(i: usize, s: &MapSegment) -> Result<(), MapFormatError> {
    for (v, field) in [
        (s.start.x, "start[0]"),
        (s.start.y, "start[1]"),
        (s.end.x, "end[0]"),
        (s.end.y, "end[1]"),
    ] {
        if !v.is_finite() {
            return Err(MapFormatError::new(
                format!("segments[{i}].{field}"),
                MapFormatErrorKind::NonFinite,
            ));
        }
    }
    if s.start == s.end {
        return Err(MapFormatError::new(
            format!("segments[{i}]"),
            MapFormatErrorKind::ZeroLength,
        ));
    }
    Ok(())
}

fn from_value(value: &Value) -> Result<LineMap, MapFormatError> {
    let top = object(value, String::new())?;
    check_fields(top, "", &["format", "version", "frame_id", "segments"])?;
    let format = required(top, "", "format")?;
    if format.as_str() != Some(MAP_FORMAT) {
        return Err(MapFormatError::wrong(
            "format".to_owned(),
            "the string \"ekf-loc line map\"",
            format,
        ));
    }
    let version = required(top, "", "version")?;
    if version.as_u64() != Some(MAP_FORMAT_VERSION) {
        return Err(MapFormatError::wrong(
            "version".to_owned(),
            "1 (the only version this reader knows)",
            version,
        ));
    }
    let frame_id = match top.get("frame_id") {
        None => super::DEFAULT_FRAME_ID.to_owned(),
        Some(Value::String(s)) => s.clone(),
        Some(other) => {
            return Err(MapFormatError::wrong(
                "frame_id".to_owned(),
                "a string",
                other,
            ))
        }
    };
    let segments = match required(top, "", "segments")? {
        Value::Array(items) => items,
        other => {
            return Err(MapFormatError::wrong(
                "segments".to_owned(),
                "an array of segments",
                other,
            ))
        }
    };
    let segments = segments
        .iter()
        .enumerate()
        .map(|(i, v)| segment(i, v))
        .collect::<Result<Vec<_>, _>>()?;
    Ok(LineMap { frame_id, segments })
}

fn segment(i: usize, value: &Value) -> Result<MapSegment, MapFormatError> {
    let path = format!("segments[{i}]");
    let obj = object(value, path.clone())?;
    check_fields(obj, &path, &["start", "end"])?;
    let start = point(required(obj, &path, "start")?, format!("{path}.start"))?;
    let end = point(required(obj, &path, "end")?, format!("{path}.end"))?;
    MapSegment::from_points(start, end)
        .map_err(|_| MapFormatError::new(path, MapFormatErrorKind::ZeroLength))
}

fn object(value: &Value, path: String) -> Result<&Map<String, Value>, MapFormatError> {
    value
        .as_object()
        .ok_or_else(|| MapFormatError::wrong(path, "an object", value))
}

fn required<'a>(
    obj: &'a Map<String, Value>,
    path: &str,
    field: &'static str,
) -> Result<&'a Value, MapFormatError> {
    obj.get(field).ok_or_else(|| {
        MapFormatError::new(path.to_owned(), MapFormatErrorKind::MissingField { field })
    })
}

fn check_fields(
    obj: &Map<String, Value>,
    path: &str,
    known: &[&str],
) -> Result<(), MapFormatError> {
    match obj.keys().find(|k| !known.contains(&k.as_str())) {
        Some(field) => Err(MapFormatError::new(
            path.to_owned(),
            MapFormatErrorKind::UnknownField {
                field: field.clone(),
            },
        )),
        None => Ok(()),
    }
}

fn point(value: &Value, path: String) -> Result<Point2<f64>, MapFormatError> {
    const EXPECTED: &str = "an array [x, y] of two finite numbers";
    let items = match value.as_array() {
        Some(items) if items.len() == 2 => items,
        _ => return Err(MapFormatError::wrong(path, EXPECTED, value)),
    };
    let mut xy = [0.0; 2];
    for (k, item) in items.iter().enumerate() {
        xy[k] = item.as_f64().filter(|v| v.is_finite()).ok_or_else(|| {
            MapFormatError::wrong(format!("{path}[{k}]"), "a finite number", item)
        })?;
    }
    Ok(Point2::new(xy[0], xy[1]))
}
