//! Rebuilding the index of a bag whose summary is missing or damaged (a recording cut
//! short): one pass over the file that checks every chunk and notes where it lies.

use super::guard::check_record;
use super::indexed::for_each_chunk_record;
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
    /// Where and why the pass stopped before the end of the file.
    pub damage: Option<SourceError>,
}

/// Reads `file` from the start up to its end or its first damage, checking each chunk's
/// CRC, and builds the summary its footer should have had. Memory: one chunk.
pub(crate) fn recover(file: &mut File) -> Recovered {
    if let Err(e) = file.seek(SeekFrom::Start(0)) {
        return Recovered {
            summary: Summary::default(),
            unchunked: false,
            damage: Some(SourceError::io(0, e)),
        };
    }
    let options = LinearReaderOptions::default()
        .with_emit_chunks(true)
        .with_validate_data_section_crc(true)
        .with_validate_summary_section_crc(true)
        .with_record_length_limit(MAX_RECORD_BYTES);
    let mut reader = LinearReader::new_with_options(options);
    let mut index = Index::default();
    let mut unchunked = false;
    // Offset of the next record: records follow the magic back to back.
    let mut pos = MAGIC_LEN;
    // Bytes read so far: where the damage is when the magic itself is cut or wrong.
    let mut fed = 0;
    let damage = loop {
        let event = match reader.next_event() {
            None => break None,
            // A wrong start magic is wrong from byte 0; a wrong end magic where it starts
            // (after the last record).
            Some(Err(McapError::BadMagic)) if pos == MAGIC_LEN => {
                break Some(SourceError::mcap(0, McapError::BadMagic))
            }
            Some(Err(e)) => break Some(SourceError::mcap(pos.min(fed), e)),
            Some(Ok(event)) => event,
        };
        let (opcode, data) = match event {
            LinearReadEvent::ReadRequest(n) => {
                match file.read(reader.insert(n.min(READ_PIECE))) {
                    Ok(read) => {
                        reader.notify_read(read);
                        fed += read as u64;
                    }
                    Err(e) => break Some(SourceError::io(pos.min(fed), e)),
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
                .map(|message| unchunked |= message)
        };
        if let Err(e) = added {
            break Some(SourceError::mcap(start, e));
        }
    };
    Recovered {
        summary: index.into_summary(),
        unchunked,
        damage,
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
