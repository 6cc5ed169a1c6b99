//! Locating a byte offset of a JSON text as a path (`segments[2].start[0]`), so syntax
//! errors name the entry they occur in.

use alloc::string::String;
use alloc::vec::Vec;
use core::fmt::Write;

/// One open container while scanning.
enum Frame {
    /// An array and the index of the element being read.
    Array(usize),
    /// An object and the key of the member being read, once known.
    Object(Option<String>),
}

/// The path of the value being read at byte `offset` of `text`, e.g.
/// `segments[1].start[0]`; empty at the top level. The scan is purely lexical (strings,
/// brackets, commas, colons), so it works on text that is not valid JSON.
pub(crate) fn path_at(text: &[u8], offset: usize) -> String {
    let mut stack: Vec<Frame> = Vec::new();
    let mut string: Option<Vec<u8>> = None;
    let mut escaped = false;
    let mut expecting_key = false;
    for &byte in &text[..offset.min(text.len())] {
        if let Some(content) = string.as_mut() {
            if escaped {
                escaped = false;
                content.push(byte);
            } else if byte == b'\\' {
                escaped = true;
            } else if byte == b'"' {
                if let (true, Some(Frame::Object(key))) = (expecting_key, stack.last_mut()) {
                    *key = Some(String::from_utf8_lossy(content).into_owned());
                    expecting_key = false;
                }
                string = None;
            } else {
                content.push(byte);
            }
            continue;
        }
        match byte {
            b'"' => string = Some(Vec::new()),
            b'{' => {
                stack.push(Frame::Object(None));
                expecting_key = true;
            }
            b'[' => stack.push(Frame::Array(0)),
            b'}' | b']' => {
                stack.pop();
                expecting_key = false;
            }
            b',' => match stack.last_mut() {
                Some(Frame::Array(i)) => *i += 1,
                Some(Frame::Object(key)) => {
                    *key = None;
                    expecting_key = true;
                }
                None => {}
            },
            _ => {}
        }
    }
    let mut path = String::new();
    for frame in &stack {
        match frame {
            Frame::Array(i) => {
                let _ = write!(path, "[{i}]");
            }
            Frame::Object(Some(key)) => {
                if !path.is_empty() {
                    path.push('.');
                }
                path.push_str(key);
            }
            Frame::Object(None) => {}
        }
    }
    path
}

/// The byte offset of a 1-based `(line, column)` position as serde_json reports it
/// (column 0 means "before the first character"), clamped to the text.
pub(crate) fn offset_of(text: &[u8], line: usize, column: usize) -> usize {
    let line_start = if line <= 1 {
        0
    } else {
        text.iter()
            .enumerate()
            .filter(|(_, &b)| b == b'\n')
            .nth(line - 2)
            .map_or(text.len(), |(i, _)| i + 1)
    };
    (line_start + column.saturating_sub(1)).min(text.len())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paths_of_nested_values() {
        let text = br#"{"a": 1, "segments": [{"start": [1, 2]}, {"start": [3, NaN"#;
        assert_eq!(path_at(text, text.len()), "segments[1].start[1]");
        assert_eq!(path_at(text, 3), "");
        assert_eq!(path_at(text, 7), "a");
        // A key containing an escaped quote and a bracket does not confuse the scan.
        let text = br#"{"we\"ird]": [0, {"x": "#;
        assert_eq!(path_at(text, text.len()), r#"we"ird][1].x"#);
    }

    #[test]
    fn line_and_column_to_offset() {
        let text = b"ab\ncde\nf";
        assert_eq!(offset_of(text, 1, 1), 0);
        assert_eq!(offset_of(text, 2, 2), 4);
        assert_eq!(offset_of(text, 3, 1), 7);
        assert_eq!(offset_of(text, 9, 9), text.len());
    }
}
