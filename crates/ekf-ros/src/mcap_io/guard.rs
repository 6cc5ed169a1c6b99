//! Length checks on MCAP records before the `mcap` crate parses them.
//!
//! The crate reads each string and byte array of a record by reserving the length its
//! prefix declares (a `u32` or `u64`) and only then reading the bytes. A corrupt prefix in
//! a record of a few bytes can so ask for up to 4 GiB: address space that a 64-bit host
//! usually grants lazily, an abort on a 32-bit robot computer. Found by the `mcap_bag`
//! fuzz target. Every record is checked here against the layout of the MCAP
//! specification (<https://mcap.dev/spec>) before it reaches the crate: each declared
//! length must fit in what is left of the record.

use mcap::records::op;
use mcap::McapError;

/// One field of a record layout.
#[derive(Clone, Copy)]
enum Field {
    /// A fixed number of bytes.
    Fixed(u64),
    /// A `u32` length, then that many bytes (strings, schema data, maps and arrays whose
    /// prefix is their byte length).
    Prefixed32,
    /// A `u32` byte length, then `string, string` pairs (channel and metadata maps).
    StringMap,
    /// A `u64` length, then that many bytes.
    Prefixed64,
    /// The rest of the record.
    Rest,
}

use Field::{Fixed, Prefixed32, Prefixed64, Rest, StringMap};

/// The layout of the record with `opcode`, up to the last length-prefixed field (fixed
/// fields after it need no check: the crate reads them from the record's own bytes).
fn layout(opcode: u8) -> &'static [Field] {
    match opcode {
        op::HEADER => &[Prefixed32, Prefixed32],
        op::SCHEMA => &[Fixed(2), Prefixed32, Prefixed32, Prefixed32],
        op::CHANNEL => &[Fixed(4), Prefixed32, Prefixed32, StringMap],
        op::CHUNK => &[Fixed(28), Prefixed32, Prefixed64],
        op::MESSAGE_INDEX => &[Fixed(2), Prefixed32],
        op::CHUNK_INDEX => &[Fixed(32), Prefixed32, Fixed(8), Prefixed32],
        op::ATTACHMENT => &[Fixed(16), Prefixed32, Prefixed32, Prefixed64],
        op::ATTACHMENT_INDEX => &[Fixed(40), Prefixed32, Prefixed32],
        op::STATISTICS => &[Fixed(42), Prefixed32],
        op::METADATA => &[Prefixed32, StringMap],
        op::METADATA_INDEX => &[Fixed(16), Prefixed32],
        _ => &[Rest],
    }
}

/// Checks that every length the record `body` (opcode `opcode`, without its opcode and
/// length prefix) declares fits in the body. The error names the opcode and the length
/// that does not fit.
pub(crate) fn check_record(opcode: u8, body: &[u8]) -> Result<(), McapError> {
    let take = |body: &[u8], at: usize, n: u64| take(opcode, body, at, n);
    let mut at = 0usize;
    for field in layout(opcode) {
        match *field {
            Fixed(n) => at = take(body, at, n)?,
            Prefixed32 => {
                let n = read_len(body, at, 4)?;
                at = take(body, at + 4, n)?;
            }
            Prefixed64 => {
                let n = read_len(body, at, 8)?;
                at = take(body, at + 8, n)?;
            }
            StringMap => {
                let n = read_len(body, at, 4)?;
                let end = take(body, at + 4, n)?;
                let mut pos = at + 4;
                while pos < end {
                    for _ in 0..2 {
                        let len = read_len(&body[..end], pos, 4)?;
                        pos = take(&body[..end], pos + 4, len)?;
                    }
                }
                at = end;
            }
            Rest => return Ok(()),
        }
    }
    Ok(())
}

/// Checks every record of `section` (records back to back: opcode, `u64` length, body),
/// as a summary section is laid out.
pub(crate) fn check_records(mut section: &[u8]) -> Result<(), McapError> {
    while !section.is_empty() {
        let opcode = section[0];
        let len = read_len(section, 1, 8)?;
        let end = take(opcode, section, 9, len)?;
        check_record(opcode, &section[9..end])?;
        section = &section[end..];
    }
    Ok(())
}

/// Checks the chunk record `body` ([`check_record`]) and, if its records are stored
/// uncompressed, their framing and layouts too ([`check_records`]): the `mcap` crate's
/// linear reader subtracts an inner record's length from what is left of an
/// uncompressed chunk without checking it (found by the `mcap_bag` fuzz target: an
/// overflow panic in debug builds, a wrapped count in release builds). Compressed
/// records are bounded by the decompressor.
pub(crate) fn check_chunk(body: &[u8]) -> Result<(), McapError> {
    check_record(op::CHUNK, body)?;
    let name_at = 28;
    let name_len = read_len(body, name_at, 4)? as usize;
    let size_at = name_at + 4 + name_len;
    // check_record has seen that the size fits in the body.
    let records_len = read_len(body, size_at, 8)? as usize;
    if name_len == 0 {
        check_records(&body[size_at + 8..size_at + 8 + records_len])?;
    }
    Ok(())
}

/// The little-endian length of `width` bytes at `at`.
fn read_len(body: &[u8], at: usize, width: usize) -> Result<u64, McapError> {
    let bytes = at
        .checked_add(width)
        .and_then(|end| body.get(at..end))
        .ok_or(McapError::UnexpectedEof)?;
    let mut le = [0u8; 8];
    le[..width].copy_from_slice(bytes);
    Ok(u64::from_le_bytes(le))
}

/// The offset after `n` bytes from `at`, if they are in `body` (of a record with
/// `opcode`).
fn take(opcode: u8, body: &[u8], at: usize, n: u64) -> Result<usize, McapError> {
    usize::try_from(n)
        .ok()
        .and_then(|n| at.checked_add(n))
        .filter(|end| *end <= body.len())
        .ok_or(McapError::RecordTooLarge { opcode, len: n })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn string(s: &str) -> Vec<u8> {
        let mut out = (s.len() as u32).to_le_bytes().to_vec();
        out.extend_from_slice(s.as_bytes());
        out
    }

    /// A channel record: id 1, schema 2, topic, encoding, one metadata pair.
    fn channel() -> Vec<u8> {
        let mut body = vec![1, 0, 2, 0];
        body.extend(string("/scan"));
        body.extend(string("cdr"));
        let pair = [string("k"), string("v")].concat();
        body.extend((pair.len() as u32).to_le_bytes());
        body.extend(pair);
        body
    }

    #[test]
    fn well_formed_records_pass_and_the_crate_agrees() {
        let body = channel();
        check_record(op::CHANNEL, &body).unwrap();
        assert!(mcap::parse_record(op::CHANNEL, &body).is_ok());
    }

    #[test]
    fn every_length_prefix_that_overruns_is_refused() {
        let body = channel();
        // Offsets of the topic, encoding, map, and the map's first key prefixes.
        for at in [4, 13, 20, 24] {
            let mut bad = body.clone();
            bad[at..at + 4].copy_from_slice(&0xfff0_0000u32.to_le_bytes());
            assert!(check_record(op::CHANNEL, &bad).is_err(), "prefix at {at}");
        }
        // Cut anywhere inside: some length no longer fits.
        for cut in 0..body.len() {
            assert!(
                check_record(op::CHANNEL, &body[..cut]).is_err(),
                "cut at {cut}"
            );
        }
    }

    #[test]
    fn a_chunk_whose_compression_name_claims_gigabytes_is_refused() {
        // The fuzz target's find: a chunk header with a 2.9 GB compression-name length.
        let mut body = vec![0u8; 28];
        body.extend(0xadf0_0000u32.to_le_bytes());
        body.extend([0u8; 16]);
        assert!(check_record(op::CHUNK, &body).is_err());
        let mut section = vec![op::CHUNK];
        section.extend((body.len() as u64).to_le_bytes());
        section.extend(&body);
        assert!(check_records(&section).is_err());
    }

    /// An uncompressed chunk holding `records`.
    fn chunk(records: &[u8]) -> Vec<u8> {
        let mut body = vec![0u8; 28];
        body.extend(0u32.to_le_bytes());
        body.extend((records.len() as u64).to_le_bytes());
        body.extend(records);
        body
    }

    #[test]
    fn an_uncompressed_chunk_whose_record_overruns_it_is_refused() {
        // The fuzz target's second find: a message record claiming more than the chunk.
        let mut message = vec![op::MESSAGE];
        message.extend(22u64.to_le_bytes());
        message.extend([0u8; 22]);
        check_chunk(&chunk(&message)).unwrap();
        assert!(mcap::parse_record(op::CHUNK, &chunk(&message)).is_ok());
        message[1..9].copy_from_slice(&23u64.to_le_bytes());
        assert!(check_chunk(&chunk(&message)).is_err());
        message[1..9].copy_from_slice(&u64::MAX.to_le_bytes());
        assert!(check_chunk(&chunk(&message)).is_err());
        // The chunk's data size, not the record's end, bounds the records.
        message[1..9].copy_from_slice(&22u64.to_le_bytes());
        let mut short = chunk(&message);
        short[32..40].copy_from_slice(&((message.len() - 1) as u64).to_le_bytes());
        assert!(check_chunk(&short).is_err());
    }
}
