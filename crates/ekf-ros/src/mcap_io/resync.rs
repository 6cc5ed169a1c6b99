//! Finding the next intact chunk record after damage in a file without a usable index:
//! a scan for a chunk opcode whose header is consistent (length inside the file, a known
//! compression, the data size matching the record length) and whose lengths and CRC
//! check, so that reading can go on there.

use super::indexed::for_each_chunk_record;
use super::source::{MAX_RECORD_BYTES, READ_PIECE};
use mcap::records::op;
use std::fs::File;
use std::io::{self, Read, Seek, SeekFrom};

/// Opcode and length prefix of a record.
const PREFIX: usize = 9;
/// A chunk body's fields before the compression name: start and end time, uncompressed
/// size (u64 each) and uncompressed CRC (u32).
const BEFORE_NAME: usize = 28;
/// The compressions a chunk can name.
const COMPRESSIONS: [&[u8]; 3] = [b"", b"zstd", b"lz4"];
/// Longest compression name.
const MAX_NAME: usize = 4;
/// Bytes of a candidate that the cheap checks read: prefix, fixed fields, name length,
/// longest name and the data size.
const HEADER_SPAN: usize = PREFIX + BEFORE_NAME + 4 + MAX_NAME + 8;

/// The offset of the first intact chunk record at or after `from` in `file` (of
/// `file_len` bytes), or `None` if there is none. Memory: a read piece and one chunk.
pub(crate) fn next_chunk(file: &mut File, from: u64, file_len: u64) -> io::Result<Option<u64>> {
    let mut window = Vec::with_capacity(READ_PIECE + HEADER_SPAN);
    let mut window_start = from;
    let mut piece = vec![0u8; READ_PIECE];
    let mut read_to = from;
    loop {
        // Keep the window holding every candidate's header: refill behind the scan point.
        if read_to < file_len {
            file.seek(SeekFrom::Start(read_to))?;
            let n = file.read(&mut piece)?;
            if n == 0 {
                return Ok(None);
            }
            window.extend_from_slice(&piece[..n]);
            read_to += n as u64;
        }
        let at_end = read_to >= file_len;
        // Candidates whose header is wholly in the window (all of them at the end).
        let scan_to = if at_end {
            window.len()
        } else {
            window.len().saturating_sub(HEADER_SPAN)
        };
        for i in 0..scan_to {
            if window[i] != op::CHUNK {
                continue;
            }
            let offset = window_start + i as u64;
            if let Some(len) = plausible_chunk(&window[i..], offset, file_len) {
                if chunk_checks(file, offset, len)? {
                    return Ok(Some(offset));
                }
            }
        }
        if at_end {
            return Ok(None);
        }
        window.drain(..scan_to);
        window_start += scan_to as u64;
    }
}

/// The body length of the chunk record starting at `bytes` (at file `offset`) if its
/// header is consistent, from the bytes at hand.
fn plausible_chunk(bytes: &[u8], offset: u64, file_len: u64) -> Option<u64> {
    let u64_at = |at: usize| {
        bytes
            .get(at..at + 8)
            .map(|b| u64::from_le_bytes(b.try_into().expect("8 bytes")))
    };
    let len = u64_at(1)?;
    let min_len = (BEFORE_NAME + 4 + 8) as u64;
    if len < min_len || len > MAX_RECORD_BYTES as u64 {
        return None;
    }
    let fits = offset
        .checked_add(PREFIX as u64 + len)
        .is_some_and(|end| end <= file_len);
    if !fits {
        return None;
    }
    let name_at = PREFIX + BEFORE_NAME;
    let name_len = bytes
        .get(name_at..name_at + 4)
        .map(|b| u32::from_le_bytes(b.try_into().expect("4 bytes")) as usize)?;
    let name = bytes.get(name_at + 4..name_at + 4 + name_len.min(MAX_NAME + 1))?;
    if name_len > MAX_NAME || !COMPRESSIONS.contains(&name) {
        return None;
    }
    let data_size = u64_at(name_at + 4 + name_len)?;
    let header_len = (BEFORE_NAME + 4 + name_len + 8) as u64;
    (data_size.checked_add(header_len) == Some(len)).then_some(len)
}

/// Whether the chunk record at `offset` with body length `len` passes the length checks
/// and its CRC.
fn chunk_checks(file: &mut File, offset: u64, len: u64) -> io::Result<bool> {
    let mut body = vec![0u8; len as usize];
    file.seek(SeekFrom::Start(offset + PREFIX as u64))?;
    file.read_exact(&mut body)?;
    Ok(for_each_chunk_record(&body, |_, _| Ok(())).is_ok())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    /// An uncompressed chunk record holding one message record (channel 1, times 5).
    fn chunk_record() -> Vec<u8> {
        let mut message = vec![op::MESSAGE];
        let body: Vec<u8> = [
            &1u16.to_le_bytes()[..],
            &0u32.to_le_bytes(),
            &5u64.to_le_bytes(),
            &5u64.to_le_bytes(),
            b"data",
        ]
        .concat();
        message.extend((body.len() as u64).to_le_bytes());
        message.extend(body);
        let mut chunk = Vec::new();
        chunk.extend(5u64.to_le_bytes());
        chunk.extend(5u64.to_le_bytes());
        chunk.extend((message.len() as u64).to_le_bytes());
        chunk.extend(crc32fast::hash(&message).to_le_bytes());
        chunk.extend(0u32.to_le_bytes());
        chunk.extend((message.len() as u64).to_le_bytes());
        chunk.extend(&message);
        let mut record = vec![op::CHUNK];
        record.extend((chunk.len() as u64).to_le_bytes());
        record.extend(chunk);
        record
    }

    fn file_with(bytes: &[u8]) -> (tempfile::TempDir, File, u64) {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("f.mcap");
        File::create(&path).unwrap().write_all(bytes).unwrap();
        (dir, File::open(&path).unwrap(), bytes.len() as u64)
    }

    #[test]
    fn the_chunk_after_junk_is_found_wherever_the_read_pieces_fall() {
        let chunk = chunk_record();
        // Junk full of chunk opcodes, then the chunk, at offsets around a read piece.
        for junk_len in [
            0,
            1,
            100,
            READ_PIECE - 20,
            READ_PIECE - 1,
            READ_PIECE,
            READ_PIECE + 7,
        ] {
            let mut bytes: Vec<u8> = (0..junk_len)
                .map(|i| if i % 3 == 0 { op::CHUNK } else { i as u8 })
                .collect();
            bytes.extend(&chunk);
            bytes.extend(b"tail");
            let (_dir, mut file, len) = file_with(&bytes);
            assert_eq!(
                next_chunk(&mut file, 0, len).unwrap(),
                Some(junk_len as u64),
                "junk {junk_len}"
            );
        }
    }

    #[test]
    fn a_chunk_opcode_before_a_huge_length_is_passed_over() {
        // The fuzz target's third find: u64::MAX as a length (the placeholder the MCAP
        // writer leaves in the chunk it was writing when a recording is killed)
        // overflowed the end offset.
        let mut bytes = vec![op::CHUNK];
        bytes.extend(u64::MAX.to_le_bytes());
        bytes.extend([0u8; 64]);
        bytes.extend(chunk_record());
        let (_dir, mut file, len) = file_with(&bytes);
        assert_eq!(next_chunk(&mut file, 0, len).unwrap(), Some(73));
    }

    #[test]
    fn a_chunk_with_a_wrong_crc_or_cut_short_is_not_a_place_to_resume() {
        let mut chunk = chunk_record();
        let last = chunk.len() - 1;
        chunk[last] ^= 1;
        let (_dir, mut file, len) = file_with(&chunk);
        assert_eq!(next_chunk(&mut file, 0, len).unwrap(), None);
        let whole = chunk_record();
        let (_dir, mut file, len) = file_with(&whole[..whole.len() - 3]);
        assert_eq!(next_chunk(&mut file, 0, len).unwrap(), None);
    }
}
