//! Finding a bag's summary section through its footer, checking it against its CRC, and
//! turning its channels into the reader's channel table.

use super::guard::check_records;
use super::message::ChannelInfo;
use super::source::{MAX_RECORD_BYTES, READ_PIECE};
use mcap::sans_io::{SummaryReadEvent, SummaryReader, SummaryReaderOptions};
use mcap::Summary;
use std::collections::HashMap;
use std::fs::File;
use std::io::{self, Read, Seek, SeekFrom};
use std::path::Path;
use std::sync::Arc;

/// Reads the summary section via the footer; `None` if the file has none or it is damaged,
/// judged by parsing and by its CRC (the caller then rebuilds it, see `recover`).
pub(crate) fn read_summary(file: &mut File, file_len: u64) -> Option<Summary> {
    if !summary_lengths_fit(file, file_len).unwrap_or(false) {
        return None;
    }
    let options = SummaryReaderOptions::default()
        .with_file_size(file_len)
        .with_record_length_limit(MAX_RECORD_BYTES);
    let mut reader = SummaryReader::new_with_options(options);
    while let Some(event) = reader.next_event() {
        match event.ok()? {
            SummaryReadEvent::ReadRequest(n) => {
                let n = file.read(reader.insert(n.min(READ_PIECE))).ok()?;
                reader.notify_read(n);
            }
            SummaryReadEvent::SeekRequest(to) => {
                reader.notify_seeked(file.seek(to).ok()?);
            }
        }
    }
    let summary = reader.finish()?;
    summary_crc_matches(file, file_len).then_some(summary)
}

/// Length of the footer record (opcode, length, body) and of the magic after it.
const FOOTER_RECORD_LEN: u64 = 1 + 8 + 20;
const MAGIC_LEN: u64 = 8;

/// Whether every length declared in the summary section fits in its record (see
/// `guard`), before the `mcap` crate parses it. True when there is no footer or no
/// summary (the summary reader reports that by itself).
fn summary_lengths_fit(file: &mut File, file_len: u64) -> io::Result<bool> {
    let Some(footer_at) = file_len.checked_sub(MAGIC_LEN + FOOTER_RECORD_LEN) else {
        return Ok(true);
    };
    let mut footer = [0u8; FOOTER_RECORD_LEN as usize];
    file.seek(SeekFrom::Start(footer_at))?;
    file.read_exact(&mut footer)?;
    if footer[0] != mcap::records::op::FOOTER {
        return Ok(true);
    }
    let summary_start = u64::from_le_bytes(footer[9..17].try_into().expect("8 bytes"));
    if summary_start == 0 {
        return Ok(true);
    }
    let Some(len) = footer_at
        .checked_sub(summary_start)
        .filter(|len| *len <= MAX_RECORD_BYTES as u64)
    else {
        return Ok(false);
    };
    let mut section = vec![0u8; len as usize];
    file.seek(SeekFrom::Start(summary_start))?;
    file.read_exact(&mut section)?;
    Ok(check_records(&section).is_ok())
}

/// Whether the summary section's CRC in the footer matches its bytes (true if the writer
/// left it 0). The CRC covers the summary section and the footer up to the CRC field.
fn summary_crc_matches(file: &mut File, file_len: u64) -> bool {
    summary_crc_check(file, file_len).unwrap_or(false)
}

/// [`summary_crc_matches`], with read errors.
fn summary_crc_check(file: &mut File, file_len: u64) -> io::Result<bool> {
    // Footer body: summary_start (u64), summary_offset_start (u64), summary_crc (u32).
    let mut footer = [0u8; 20];
    file.seek(SeekFrom::Start(file_len.saturating_sub(MAGIC_LEN + 20)))?;
    file.read_exact(&mut footer)?;
    let [s0, s1, s2, s3, s4, s5, s6, s7, .., c0, c1, c2, c3] = footer;
    let summary_start = u64::from_le_bytes([s0, s1, s2, s3, s4, s5, s6, s7]);
    let saved = u32::from_le_bytes([c0, c1, c2, c3]);
    if saved == 0 {
        return Ok(true);
    }
    let end = file_len.saturating_sub(MAGIC_LEN + 4);
    if summary_start > end {
        return Ok(false);
    }
    file.seek(SeekFrom::Start(summary_start))?;
    let mut hasher = crc32fast::Hasher::new();
    let mut piece = vec![0u8; READ_PIECE];
    let mut left = end - summary_start;
    while left > 0 {
        let n = left.min(READ_PIECE as u64) as usize;
        file.read_exact(&mut piece[..n])?;
        hasher.update(&piece[..n]);
        left -= n as u64;
    }
    Ok(hasher.finalize() == saved)
}

/// Builds the channel table from `summary`, keeping channels without schema (type name "").
pub(crate) fn summary_channels(
    summary: &Summary,
    path: &Arc<Path>,
) -> HashMap<u16, Arc<ChannelInfo>> {
    summary
        .channels
        .iter()
        .map(|(&id, c)| {
            let (type_name, schema_encoding) = c
                .schema
                .as_ref()
                .map(|s| (s.name.clone(), s.encoding.clone()))
                .unwrap_or_default();
            let info = ChannelInfo {
                path: Arc::clone(path),
                topic: c.topic.clone(),
                type_name,
                schema_encoding,
                message_encoding: c.message_encoding.clone(),
            };
            (id, Arc::new(info))
        })
        .collect()
}
