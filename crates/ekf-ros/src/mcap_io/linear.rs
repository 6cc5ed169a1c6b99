//! Messages in file order, around the `mcap` crate's sans-io `LinearReader`: for files
//! with messages outside chunks, which no chunk index reaches.

use super::message::ChannelInfo;
use super::source::{Raw, SourceError, MAX_RECORD_BYTES, READ_PIECE};
use mcap::records::Record;
use mcap::sans_io::{LinearReadEvent, LinearReader, LinearReaderOptions};
use std::collections::HashMap;
use std::fs::File;
use std::io::Read;
use std::path::Path;
use std::sync::Arc;

/// Messages in file order from any MCAP, including a damaged one: every message before
/// the damage, then the error. Each chunk's CRC is checked before any of its messages is
/// delivered. Memory: one chunk.
pub(crate) struct LinearSource {
    file: File,
    reader: LinearReader,
    /// Bytes of the file handed to the reader so far.
    fed: u64,
    /// Schema id → (name, encoding).
    schemas: HashMap<u16, (String, String)>,
    channels: HashMap<u16, Arc<ChannelInfo>>,
    path: Arc<Path>,
}

impl LinearSource {
    /// Starts reading `file` from its beginning.
    pub fn new(file: File, path: Arc<Path>) -> Self {
        let options = LinearReaderOptions::default()
            .with_prevalidate_chunk_crcs(true)
            .with_validate_data_section_crc(true)
            .with_validate_summary_section_crc(true)
            .with_record_length_limit(MAX_RECORD_BYTES);
        Self {
            file,
            reader: LinearReader::new_with_options(options),
            fed: 0,
            schemas: HashMap::new(),
            channels: HashMap::new(),
            path,
        }
    }

    /// The next message, `None` after the last.
    pub fn next(&mut self) -> Option<Result<Raw, SourceError>> {
        loop {
            let offset = self.fed;
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
            match mcap::parse_record(opcode, data) {
                Err(source) => return corrupt(source),
                Ok(Record::Schema { header, .. }) => {
                    self.schemas
                        .insert(header.id, (header.name, header.encoding));
                }
                Ok(Record::Channel(c)) => {
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
                Ok(Record::Message { header, data }) => {
                    let Some(channel) = self.channels.get(&header.channel_id) else {
                        return Some(Err(SourceError::UnknownChannel(header.channel_id)));
                    };
                    return Some(Ok(Raw {
                        channel: Arc::clone(channel),
                        log_time: header.log_time,
                        publish_time: header.publish_time,
                        data: data.into_owned(),
                    }));
                }
                Ok(_) => {}
            }
        }
    }
}
