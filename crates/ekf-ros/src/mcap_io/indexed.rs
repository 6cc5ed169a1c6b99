//! Messages in log-time order through the chunk indexes, around the `mcap` crate's sans-io
//! `IndexedReader`, with each chunk's CRC checked before any of its messages is delivered.

use super::error::LostRange;
use super::guard::{check_chunk, check_record};
use super::message::ChannelInfo;
use super::source::{Raw, SourceError, MAX_RECORD_BYTES};
use mcap::records::{op, ChunkIndex, Record};
use mcap::sans_io::indexed_reader::ReadOrder;
use mcap::sans_io::{
    IndexedReadEvent, IndexedReader, IndexedReaderOptions, LinearReadEvent, LinearReader,
    LinearReaderOptions,
};
use mcap::{McapError, Summary};
use std::collections::HashMap;
use std::fs::File;
use std::io::{Read, Seek, SeekFrom};
use std::sync::Arc;

/// Messages in log-time order (ties in file order) from a file with chunk indexes. Each
/// chunk's CRC is checked before any of its messages is delivered; a damaged chunk is
/// reported ([`SourceError::Skipped`]) and passed over, and reading goes on with the next.
/// Memory: the chunks whose time ranges overlap the current message, one chunk in the
/// usual case.
pub(crate) struct IndexedSource {
    file: File,
    file_len: u64,
    reader: IndexedReader,
    /// The summary with the damaged chunks left out, to restart the reader from.
    summary: Summary,
    /// Log time of the last message delivered, and how many had that time.
    last: Option<(u64, u64)>,
    /// Messages at the last log time to pass over after a restart (delivered before it).
    redelivered: u64,
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
        let reader = reader_from(summary, None).map_err(|e| SourceError::mcap(0, e))?;
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
            summary: summary.clone(),
            last: None,
            redelivered: 0,
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
                    match self.load_chunk(offset) {
                        Ok(()) => {}
                        Err(SourceError::Mcap { offset: at, source }) => {
                            return Some(Err(self.skip_chunk(offset, at, source)));
                        }
                        Err(e) => return Some(Err(e)),
                    }
                }
                IndexedReadEvent::Message { header, data } => {
                    let t = header.log_time;
                    let same_time = self.last.filter(|(last, _)| *last == t);
                    if self.redelivered > 0 && same_time.is_some() {
                        self.redelivered -= 1;
                        continue;
                    }
                    self.redelivered = 0;
                    self.last = Some((t, same_time.map_or(1, |(_, n)| n + 1)));
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

    /// Leaves the damaged chunk whose data starts at `data_offset` out of the summary and
    /// restarts the reader at the last log time delivered (passing over the messages at
    /// that time already delivered). Returns the report of the skip, or the error that
    /// ends the stream if the reader cannot restart.
    fn skip_chunk(&mut self, data_offset: u64, at: u64, source: Arc<McapError>) -> SourceError {
        let Some(index) = self.chunks.remove(&data_offset) else {
            return SourceError::Mcap { offset: at, source };
        };
        let lost = LostRange {
            from_ns: Some(index.message_start_time),
            to_ns: Some(index.message_end_time),
        };
        let start = index.chunk_start_offset;
        // Every index entry whose data starts there (a hostile summary can list two): the
        // reader is never asked for that data again, so a restart always makes progress.
        self.summary
            .chunk_indexes
            .retain(|c| c.compressed_data_offset().ok() != Some(data_offset));
        match reader_from(&self.summary, self.last.map(|(t, _)| t)) {
            Ok(reader) => self.reader = reader,
            Err(e) => return SourceError::mcap(start, e),
        }
        self.redelivered = self.last.map_or(0, |(_, n)| n);
        SourceError::Skipped {
            offset: at,
            lost,
            source,
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
        check_record(op::CHUNK, &self.buf[9..]).map_err(corrupt)?;
        let (header, data) = match mcap::parse_record(op::CHUNK, &self.buf[9..]) {
            Ok(Record::Chunk { header, data }) => (header, data),
            Ok(_) => return Err(corrupt(McapError::BadIndex)),
            Err(e) => return Err(corrupt(e)),
        };
        if header.compressed_size != data.len() as u64 {
            return Err(corrupt(McapError::BadIndex));
        }
        for_each_chunk_record(&self.buf[9..], |_, _| Ok(())).map_err(corrupt)?;
        self.reader
            .insert_chunk_record_data(data_offset, &data)
            .map_err(corrupt)
    }
}

/// An indexed reader over `summary`'s chunks in log-time order, from log time `from_ns`.
fn reader_from(summary: &Summary, from_ns: Option<u64>) -> Result<IndexedReader, McapError> {
    let mut options = IndexedReaderOptions::new().with_order(ReadOrder::LogTime);
    if let Some(t) = from_ns {
        options = options.starting_at(t);
    }
    options.record_length_limit = Some(MAX_RECORD_BYTES);
    IndexedReader::new_with_options(summary, options)
}

/// Checks the lengths of the chunk record whose body (without opcode and length) is
/// `body` ([`check_chunk`]), decompresses it, checks its CRC before anything else, then
/// calls `each(opcode, body)` for every record inside it. Uses the same size limit as
/// the readers.
pub(crate) fn for_each_chunk_record(
    body: &[u8],
    mut each: impl FnMut(u8, &[u8]) -> Result<(), McapError>,
) -> Result<(), McapError> {
    check_chunk(body)?;
    let options = LinearReaderOptions::default()
        .with_skip_start_magic(true)
        .with_skip_end_magic(true)
        .with_prevalidate_chunk_crcs(true)
        .with_record_length_limit(MAX_RECORD_BYTES);
    let mut reader = LinearReader::new_with_options(options);
    let mut prefix = [0u8; 9];
    prefix[0] = op::CHUNK;
    prefix[1..].copy_from_slice(&(body.len() as u64).to_le_bytes());
    let mut pieces = [&prefix[..], body];
    let mut current = 0;
    while let Some(event) = reader.next_event() {
        match event? {
            LinearReadEvent::ReadRequest(n) => {
                while current < pieces.len() && pieces[current].is_empty() {
                    current += 1;
                }
                let rest = pieces.get(current).copied().unwrap_or_default();
                let (piece, tail) = rest.split_at(n.min(rest.len()));
                reader.insert(piece.len()).copy_from_slice(piece);
                reader.notify_read(piece.len());
                if let Some(p) = pieces.get_mut(current) {
                    *p = tail;
                }
            }
            LinearReadEvent::Record { opcode, data } => each(opcode, data)?,
        }
    }
    Ok(())
}
