//! Messages in file order, around the `mcap` crate's sans-io `LinearReader`: for files
//! with messages outside chunks, which no chunk index reaches.

use super::guard::check_record;
use super::indexed::for_each_chunk_record;
use super::message::ChannelInfo;
use super::source::{Raw, SourceError, MAX_RECORD_BYTES, READ_PIECE};
use mcap::records::{op, Record};
use mcap::sans_io::{LinearReadEvent, LinearReader, LinearReaderOptions};
use mcap::McapError;
use std::collections::{HashMap, VecDeque};
use std::fs::File;
use std::io::Read;
use std::path::Path;
use std::sync::Arc;

/// Messages in file order from any MCAP, including a damaged one: every message before
/// the damage, then the error. Each chunk's lengths and CRC are checked before any of its
/// messages is delivered. Memory: one chunk.
pub(crate) struct LinearSource {
    file: File,
    reader: LinearReader,
    /// Bytes of the file handed to the reader so far.
    fed: u64,
    /// The records of the chunk being read, not yet handled, in order.
    pending: VecDeque<(u8, Vec<u8>)>,
    table: Table,
}

/// The schemas and channels defined so far.
struct Table {
    /// Schema id → (name, encoding).
    schemas: HashMap<u16, (String, String)>,
    channels: HashMap<u16, Arc<ChannelInfo>>,
    path: Arc<Path>,
}

impl LinearSource {
    /// Starts reading `file` from its beginning.
    pub fn new(file: File, path: Arc<Path>) -> Self {
        // Chunks come out whole, so that their headers are checked here before the
        // `mcap` crate parses them (see `guard`).
        let options = LinearReaderOptions::default()
            .with_emit_chunks(true)
            .with_validate_data_section_crc(true)
            .with_validate_summary_section_crc(true)
            .with_record_length_limit(MAX_RECORD_BYTES);
        Self {
            file,
            reader: LinearReader::new_with_options(options),
            fed: 0,
            pending: VecDeque::new(),
            table: Table {
                schemas: HashMap::new(),
                channels: HashMap::new(),
                path,
            },
        }
    }

    /// The next message, `None` after the last.
    pub fn next(&mut self) -> Option<Result<Raw, SourceError>> {
        loop {
            let offset = self.fed;
            if let Some((opcode, data)) = self.pending.pop_front() {
                match self.table.handle(opcode, &data) {
                    Ok(None) => continue,
                    Ok(Some(raw)) => return Some(Ok(raw)),
                    Err(e) => return Some(Err(e.at(offset))),
                }
            }
            let corrupt = |e| Some(Err(SourceError::mcap(offset, e)));
            let (opcode, data) = match self.reader.next_event()? {
                Err(source) => return corrupt(source),
                Ok(LinearReadEvent::ReadRequest(n)) => {
                    let buf = self.reader.insert(n.min(READ_PIECE));
                    match self.file.read(buf) {
                        Ok(read) => {
                            self.reader.notify_read(read);
                            self.fed += read as u64;
                        }
                        Err(e) => return Some(Err(SourceError::io(offset, e))),
                    }
                    continue;
                }
                Ok(LinearReadEvent::Record { opcode, data }) => (opcode, data),
            };
            if opcode == op::CHUNK {
                if let Err(e) = unpack_chunk(data, &mut self.pending) {
                    return corrupt(e);
                }
                continue;
            }
            match self.table.handle(opcode, data) {
                Ok(None) => {}
                Ok(Some(raw)) => return Some(Ok(raw)),
                Err(e) => return Some(Err(e.at(offset))),
            }
        }
    }
}

impl Table {
    /// Notes a schema or channel; a message becomes a [`Raw`].
    fn handle(&mut self, opcode: u8, data: &[u8]) -> Result<Option<Raw>, Failure> {
        check_record(opcode, data).map_err(Failure::Mcap)?;
        match mcap::parse_record(opcode, data).map_err(Failure::Mcap)? {
            Record::Schema { header, .. } => {
                self.schemas
                    .insert(header.id, (header.name, header.encoding));
            }
            Record::Channel(c) => {
                let (type_name, schema_encoding) =
                    self.schemas.get(&c.schema_id).cloned().unwrap_or_default();
                let info = ChannelInfo {
                    path: Arc::clone(&self.path),
                    topic: c.topic,
                    type_name,
                    schema_encoding,
                    message_encoding: c.message_encoding,
                };
                self.channels.insert(c.id, Arc::new(info));
            }
            Record::Message { header, data } => {
                let channel = self
                    .channels
                    .get(&header.channel_id)
                    .ok_or(Failure::UnknownChannel(header.channel_id))?;
                return Ok(Some(Raw {
                    channel: Arc::clone(channel),
                    log_time: header.log_time,
                    publish_time: header.publish_time,
                    data: data.into_owned(),
                }));
            }
            _ => {}
        }
        Ok(None)
    }
}

/// Why a record could not be handled, before the offset is known.
enum Failure {
    Mcap(McapError),
    UnknownChannel(u16),
}

impl Failure {
    fn at(self, offset: u64) -> SourceError {
        match self {
            Failure::Mcap(e) => SourceError::mcap(offset, e),
            Failure::UnknownChannel(id) => SourceError::UnknownChannel(id),
        }
    }
}

/// Checks the chunk record `body` (lengths, then CRC) and queues the records inside it.
fn unpack_chunk(body: &[u8], pending: &mut VecDeque<(u8, Vec<u8>)>) -> Result<(), McapError> {
    for_each_chunk_record(body, |opcode, data| {
        pending.push_back((opcode, data.to_vec()));
        Ok(())
    })
}
