//! Rebuilding the index of a bag whose summary is missing or damaged (a recording cut
//! short): one pass over the file that checks every chunk and notes where it lies, going
//! on at the next intact chunk after damage.

use super::error::LostRange;
use super::guard::check_record;
use super::indexed::for_each_chunk_record;
use super::resync::next_chunk;
use super::source::{SourceError, MAX_RECORD_BYTES, READ_PIECE};
use mcap::records::{op, ChunkIndex, Record, Statistics};
use mcap::sans_io::{LinearReadEvent, LinearReader, LinearReaderOptions};
use mcap::{Channel, McapError, Schema, Summary};
use std::borrow::Cow;
use std::collections::{BTreeMap, HashMap};
use std::fs::File;
use std::io::{Read, Seek, SeekFrom};
use std::sync::Arc;

/// Length of a record's opcode and length prefix.
const PREFIX: u64 = 9;
/// Length of the magic at the start of the file.
const MAGIC_LEN: u64 = 8;

/// What the pass found.
pub(crate) struct Recovered {
    /// Schemas, channels, message counts and one index entry per intact chunk.
    pub summary: Summary,
    /// Whether messages outside chunks were found, which a chunk index cannot reach.
    pub unchunked: bool,
    /// Damage that was read past ([`SourceError::Skipped`]), in file order: reading went
    /// on at the next intact chunk after each.
    pub skipped: Vec<SourceError>,
    /// Where and why the pass stopped before the end of the file, with no intact chunk
    /// after it (a recording cut short).
    pub damage: Option<SourceError>,
}

/// Reads `file` from the start to its end, checking each chunk's lengths and CRC, and
/// builds the summary its footer should have had. After damage it goes on at the next
/// intact chunk record (found by [`next_chunk`]), so a damaged chunk in the middle loses
/// only itself. Memory: one chunk.
pub(crate) fn recover(file: &mut File) -> Recovered {
    let file_len = match file.metadata() {
        Ok(m) => m.len(),
        Err(e) => {
            return Recovered {
                summary: Summary::default(),
                unchunked: false,
                skipped: Vec::new(),
                damage: Some(SourceError::io(0, e)),
            }
        }
    };
    let mut index = Index::default();
    let mut unchunked = false;
    // (where the damage was found, why, where reading went on)
    let mut passed: Vec<(u64, Arc<McapError>, u64)> = Vec::new();
    let mut from = 0;
    let damage = loop {
        let Some(damage) = pass(file, from, &mut index, &mut unchunked) else {
            break None;
        };
        let (at, source) = match &damage {
            SourceError::Mcap { offset, source } => (*offset, Arc::clone(source)),
            _ => break Some(damage),
        };
        match next_chunk(file, at.max(from) + 1, file_len) {
            Ok(Some(next)) => {
                passed.push((at, source, next));
                from = next;
            }
            Ok(None) => break Some(damage),
            Err(e) => break Some(SourceError::io(at, e)),
        }
    };
    let skipped = passed
        .into_iter()
        .map(|(offset, source, resumed)| SourceError::Skipped {
            offset,
            lost: index.lost_between(offset, resumed),
            source,
        })
        .collect();
    Recovered {
        summary: index.into_summary(),
        unchunked,
        skipped,
        damage,
    }
}

/// One linear pass over `file` from `from` (0: the start, with its magic; else a chunk
/// record found by [`next_chunk`]) to the end or the first damage, adding what it finds
/// to `index`. Returns the damage.
fn pass(
    file: &mut File,
    from: u64,
    index: &mut Index,
    unchunked: &mut bool,
) -> Option<SourceError> {
    if let Err(e) = file.seek(SeekFrom::Start(from)) {
        return Some(SourceError::io(from, e));
    }
    // The data section's CRC covers it from the start: only a pass from there checks it.
    let options = LinearReaderOptions::default()
        .with_emit_chunks(true)
        .with_skip_start_magic(from > 0)
        .with_validate_data_section_crc(from == 0)
        .with_validate_summary_section_crc(true)
        .with_record_length_limit(MAX_RECORD_BYTES);
    let mut reader = LinearReader::new_with_options(options);
    // Offset of the next record: records follow the magic back to back.
    let mut pos = if from == 0 { MAGIC_LEN } else { from };
    // End of the bytes read so far: where the damage is when the magic itself is cut or
    // wrong.
    let mut fed = from;
    loop {
        let event = match reader.next_event() {
            None => return None,
            // A wrong start magic is wrong from byte 0; a wrong end magic where it starts
            // (after the last record).
            Some(Err(McapError::BadMagic)) if pos == MAGIC_LEN => {
                return Some(SourceError::mcap(0, McapError::BadMagic))
            }
            Some(Err(e)) => return Some(SourceError::mcap(pos.min(fed), e)),
            Some(Ok(event)) => event,
        };
        let (opcode, data) = match event {
            LinearReadEvent::ReadRequest(n) => {
                match file.read(reader.insert(n.min(READ_PIECE))) {
                    Ok(read) => {
                        reader.notify_read(read);
                        fed += read as u64;
                    }
                    Err(e) => return Some(SourceError::io(pos.min(fed), e)),
                }
                continue;
            }
            LinearReadEvent::Record { opcode, data } => (opcode, data),
        };
        let start = pos;
        pos += PREFIX + data.len() as u64;
        let added = if opcode == op::CHUNK {
            index.add_chunk(start, data)
        } else {
            index
                .add_record(opcode, data)
                .map(|message| *unchunked |= message)
        };
        if let Err(e) = added {
            return Some(SourceError::mcap(start, e));
        }
    }
}

/// The summary being rebuilt.
#[derive(Default)]
struct Index {
    schemas: HashMap<u16, Arc<Schema<'static>>>,
    channels: HashMap<u16, Arc<Channel<'static>>>,
    chunks: Vec<ChunkIndex>,
    counts: BTreeMap<u16, u64>,
}

impl Index {
    /// Notes a schema or channel; returns whether the record was a message.
    fn add_record(&mut self, opcode: u8, data: &[u8]) -> Result<bool, McapError> {
        check_record(opcode, data)?;
        match mcap::parse_record(opcode, data)? {
            Record::Schema { header, data } => {
                let schema = Schema {
                    id: header.id,
                    name: header.name,
                    encoding: header.encoding,
                    data: Cow::Owned(data.into_owned()),
                };
                self.schemas.insert(header.id, Arc::new(schema));
            }
            Record::Channel(c) => {
                let channel = Channel {
                    id: c.id,
                    topic: c.topic,
                    schema: self.schemas.get(&c.schema_id).cloned(),
                    message_encoding: c.message_encoding,
                    metadata: c.metadata,
                };
                self.channels.insert(c.id, Arc::new(channel));
            }
            Record::Message { header, .. } => {
                *self.counts.entry(header.channel_id).or_default() += 1;
                return Ok(true);
            }
            _ => {}
        }
        Ok(false)
    }

    /// Checks the chunk record starting at `start` (body `body`), notes the schemas,
    /// channels and messages inside, and adds its index entry.
    fn add_chunk(&mut self, start: u64, body: &[u8]) -> Result<(), McapError> {
        check_record(op::CHUNK, body)?;
        let Record::Chunk { header, data } = mcap::parse_record(op::CHUNK, body)? else {
            return Err(McapError::BadIndex);
        };
        if header.compressed_size != data.len() as u64 {
            return Err(McapError::BadChunkLength {
                header: header.compressed_size,
                available: data.len() as u64,
            });
        }
        for_each_chunk_record(body, |opcode, data| {
            self.add_record(opcode, data).map(|_| ())
        })?;
        self.chunks.push(ChunkIndex {
            message_start_time: header.message_start_time,
            message_end_time: header.message_end_time,
            chunk_start_offset: start,
            chunk_length: PREFIX + body.len() as u64,
            message_index_offsets: BTreeMap::new(),
            message_index_length: 0,
            compression: header.compression,
            compressed_size: header.compressed_size,
            uncompressed_size: header.uncompressed_size,
        });
        Ok(())
    }

    /// The log times around the stretch from byte `damaged` to `resumed`: the latest end
    /// time of the intact chunks before it, the earliest start time of those after.
    fn lost_between(&self, damaged: u64, resumed: u64) -> LostRange {
        let before = self
            .chunks
            .iter()
            .filter(|c| c.chunk_start_offset < damaged);
        let after = self
            .chunks
            .iter()
            .filter(|c| c.chunk_start_offset >= resumed);
        LostRange {
            from_ns: before.map(|c| c.message_end_time).max(),
            to_ns: after.map(|c| c.message_start_time).min(),
        }
    }

    /// The rebuilt summary, with per-channel message counts as statistics.
    fn into_summary(self) -> Summary {
        let stats = Statistics {
            message_count: self.counts.values().sum(),
            channel_message_counts: self.counts,
            ..Statistics::default()
        };
        Summary {
            stats: Some(stats),
            channels: self.channels,
            schemas: self.schemas,
            chunk_indexes: self.chunks,
            ..Summary::default()
        }
    }
}
