//! The I/O loops around the `mcap` crate's sans-io readers: one that follows the chunk
//! indexes of a finished file (log-time order), one that reads a damaged file front to back.

use super::message::ChannelInfo;
use mcap::records::{op, ChunkIndex, Record};
use mcap::sans_io::indexed_reader::ReadOrder;
use mcap::sans_io::{
    IndexedReadEvent, IndexedReader, IndexedReaderOptions, LinearReadEvent, LinearReader,
    LinearReaderOptions, SummaryReadEvent, SummaryReader, SummaryReaderOptions,
};
use mcap::{McapError, Summary};
use std::collections::HashMap;
use std::fs::File;
use std::io::{self, Read, Seek, SeekFrom};
use std::path::Path;
use std::sync::Arc;

/// Largest record or decompressed chunk accepted (256 MiB). rosbag2 writes 4 MiB chunks;
/// the cap keeps a corrupt length field from requesting gigabytes of memory.
pub(crate) const MAX_RECORD_BYTES: usize = 256 << 20;

/// Largest piece read from the file at once.
pub(crate) const READ_PIECE: usize = 64 << 10;

/// A message as read, before it is numbered.
pub(crate) struct Raw {
    /// Its channel.
    pub channel: Arc<ChannelInfo>,
    /// Log time (ns).
    pub log_time: u64,
    /// Publish time (ns).
    pub publish_time: u64,
    /// CDR payload.
    pub data: Vec<u8>,
}

/// Why a source stopped, with the byte offset it had reached. Cloneable, so the damage a
/// recovery pass found can be reported by every stream over the file.
#[derive(Debug, Clone)]
pub(crate) enum SourceError {
    /// The parser rejected the data at `offset`.
    Mcap { offset: u64, source: Arc<McapError> },
    /// Reading at `offset` failed.
    Io { offset: u64, source: Arc<io::Error> },
    /// A message named a channel that was never defined.
    UnknownChannel(u16),
}

impl SourceError {
    /// A parser error at `offset`.
    pub fn mcap(offset: u64, source: McapError) -> Self {
        Self::Mcap {
            offset,
            source: Arc::new(source),
        }
    }

    /// A read error at `offset`.
    pub fn io(offset: u64, source: io::Error) -> Self {
        Self::Io {
            offset,
            source: Arc::new(source),
        }
    }
}

/// Reads the summary section via the footer; `None` if the file has none or it is damaged,
/// judged by parsing and by its CRC (the caller then reads the file front to back).
pub(crate) fn read_summary(file: &mut File, file_len: u64) -> Option<Summary> {
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

/// Whether the summary section's CRC in the footer matches its bytes (true if the writer
/// left it 0). The CRC covers the summary section and the footer up to the CRC field.
fn summary_crc_matches(file: &mut File, file_len: u64) -> bool {
    summary_crc_check(file, file_len).unwrap_or(false)
}

/// [`summary_crc_matches`], with read errors.
fn summary_crc_check(file: &mut File, file_len: u64) -> io::Result<bool> {
    const MAGIC_LEN: u64 = 8;
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

/// Messages in log-time order (ties in file order) from a file with chunk indexes. Each
/// chunk's CRC is checked before any of its messages is delivered. Memory: the chunks whose
/// time ranges overlap the current message, one chunk in the usual case.
pub(crate) struct IndexedSource {
    file: File,
    file_len: u64,
    reader: IndexedReader,
    channels: HashMap<u16, Arc<ChannelInfo>>,
    /// Chunk records by the offset of their compressed data (what the reader asks for).
    chunks: HashMap<u64, ChunkIndex>,
    buf: Vec<u8>,
    /// Start of the chunk read last, for error messages.
    offset: u64,
}

impl IndexedSource {
    /// Prepares to read the chunks `summary` indexes.
    pub fn new(
        file: File,
        file_len: u64,
        summary: &Summary,
        channels: HashMap<u16, Arc<ChannelInfo>>,
    ) -> Result<Self, SourceError> {
        let mut options = IndexedReaderOptions::new().with_order(ReadOrder::LogTime);
        options.record_length_limit = Some(MAX_RECORD_BYTES);
        let reader = IndexedReader::new_with_options(summary, options)
            .map_err(|e| SourceError::mcap(0, e))?;
        let mut chunks = HashMap::new();
        for c in &summary.chunk_indexes {
            let at = c
                .compressed_data_offset()
                .map_err(|e| SourceError::mcap(c.chunk_start_offset, e))?;
            chunks.insert(at, c.clone());
        }
        Ok(Self {
            file,
            file_len,
            reader,
            channels,
            chunks,
            buf: Vec::new(),
            offset: 0,
        })
    }

    /// The next message, `None` after the last.
    pub fn next(&mut self) -> Option<Result<Raw, SourceError>> {
        loop {
            let event = match self.reader.next_event()? {
                Ok(e) => e,
                Err(source) => {
                    let offset = self.offset;
                    return Some(Err(SourceError::mcap(offset, source)));
                }
            };
            match event {
                IndexedReadEvent::ReadChunkRequest { offset, .. } => {
                    if let Err(e) = self.load_chunk(offset) {
                        return Some(Err(e));
                    }
                }
                IndexedReadEvent::Message { header, data } => {
                    let Some(channel) = self.channels.get(&header.channel_id) else {
                        return Some(Err(SourceError::UnknownChannel(header.channel_id)));
                    };
                    return Some(Ok(Raw {
                        channel: Arc::clone(channel),
                        log_time: header.log_time,
                        publish_time: header.publish_time,
                        data: data.to_vec(),
                    }));
                }
            }
        }
    }

    /// Reads the whole chunk record whose data starts at `data_offset`, checks its CRC and
    /// hands its data to the indexed reader.
    fn load_chunk(&mut self, data_offset: u64) -> Result<(), SourceError> {
        let index = self
            .chunks
            .get(&data_offset)
            .ok_or_else(|| SourceError::mcap(data_offset, McapError::BadIndex))?;
        let start = index.chunk_start_offset;
        self.offset = start;
        let corrupt = |e| SourceError::mcap(start, e);
        let fits = start
            .checked_add(index.chunk_length)
            .is_some_and(|end| end <= self.file_len);
        if !fits || index.chunk_length < 9 {
            return Err(corrupt(McapError::BadIndex));
        }
        self.buf.resize(index.chunk_length as usize, 0);
        self.file
            .seek(SeekFrom::Start(start))
            .and_then(|_| self.file.read_exact(&mut self.buf))
            .map_err(|e| SourceError::io(start, e))?;
        if self.buf[0] != op::CHUNK {
            return Err(corrupt(McapError::BadIndex));
        }
        let (header, data) = match mcap::parse_record(op::CHUNK, &self.buf[9..]) {
            Ok(Record::Chunk { header, data }) => (header, data),
            Ok(_) => return Err(corrupt(McapError::BadIndex)),
            Err(e) => return Err(corrupt(e)),
        };
        if header.compressed_size != data.len() as u64 {
            return Err(corrupt(McapError::BadIndex));
        }
        for_each_chunk_record(&self.buf, |_, _| Ok(())).map_err(corrupt)?;
        self.reader
            .insert_chunk_record_data(data_offset, &data)
            .map_err(corrupt)
    }
}

/// Decompresses the chunk record `record` (opcode and length included), checks its CRC
/// before anything else, then calls `each(opcode, body)` for every record inside it. Uses
/// the same size limit as the readers.
pub(crate) fn for_each_chunk_record(
    record: &[u8],
    mut each: impl FnMut(u8, &[u8]) -> Result<(), McapError>,
) -> Result<(), McapError> {
    let options = LinearReaderOptions::default()
        .with_skip_start_magic(true)
        .with_skip_end_magic(true)
        .with_prevalidate_chunk_crcs(true)
        .with_record_length_limit(MAX_RECORD_BYTES);
    let mut reader = LinearReader::new_with_options(options);
    let mut rest = record;
    while let Some(event) = reader.next_event() {
        match event? {
            LinearReadEvent::ReadRequest(n) => {
                let (piece, tail) = rest.split_at(n.min(rest.len()));
                reader.insert(piece.len()).copy_from_slice(piece);
                reader.notify_read(piece.len());
                rest = tail;
            }
            LinearReadEvent::Record { opcode, data } => each(opcode, data)?,
        }
    }
    Ok(())
}

/// Messages in file order from any MCAP, including a truncated one: every message before
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
