//! A sans-I/O parser of the byte stream from (or to) an LMS 2xx: bytes in, events out —
//! telegrams, ACK/NAK, and every discarded byte run with the reason and its stream offset.
//! It resynchronises after garbage, bad CRCs and truncated telegrams without losing a
//! valid telegram that starts inside a damaged one.

use super::crc::crc16;
use super::telegram::{Telegram, ACK, FRAME_OVERHEAD, MAX_LEN, NAK, STX};

/// Why bytes were thrown away.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DiscardKind {
    /// Bytes outside any telegram (or an STX with an impossible LEN).
    Garbage,
    /// A complete telegram whose CRC does not match.
    BadCrc {
        /// The CRC computed over the received bytes.
        expected: u16,
        /// The CRC the telegram carried.
        found: u16,
    },
    /// A telegram cut short: another telegram starts before its end, or the stream
    /// stopped inside it.
    Truncated,
}

/// A run of discarded bytes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Discard {
    /// Stream offset of the first discarded byte (bytes pushed since the parser started).
    pub offset: u64,
    /// Number of bytes discarded.
    pub len: usize,
    /// Why.
    pub kind: DiscardKind,
}

impl std::fmt::Display for Discard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let (offset, len) = (self.offset, self.len);
        match self.kind {
            DiscardKind::Garbage => write!(
                f,
                "{len} garbage bytes at byte offset {offset} (expected STX 02, ACK 06 or NAK 15)"
            ),
            DiscardKind::BadCrc { expected, found } => write!(
                f,
                "telegram of {len} bytes at byte offset {offset} has CRC {found:04x}, expected {expected:04x}"
            ),
            DiscardKind::Truncated => {
                write!(f, "telegram at byte offset {offset} truncated after {len} bytes")
            }
        }
    }
}

/// What the parser found in the stream.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Event {
    /// A telegram with a valid CRC.
    Telegram(Telegram),
    /// An acknowledge byte.
    Ack,
    /// A not-acknowledge byte.
    Nak,
    /// Bytes that were thrown away.
    Discarded(Discard),
}

/// Counts of what the parser has seen.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct ParserStats {
    /// Telegrams with a valid CRC.
    pub telegrams: u64,
    /// Garbage bytes outside telegrams.
    pub garbage_bytes: u64,
    /// Complete telegrams with a wrong CRC.
    pub bad_crc: u64,
    /// Telegrams cut short.
    pub truncated: u64,
}

/// The streaming telegram parser.
#[derive(Debug, Default)]
pub struct TelegramParser {
    buf: Vec<u8>,
    /// Stream offset of `buf[0]`.
    offset: u64,
    stats: ParserStats,
}

/// What the bytes at the start of a buffer are.
enum Head {
    /// Not enough bytes yet.
    NeedMore,
    /// A complete telegram of this many bytes with a valid CRC.
    Valid(usize),
    /// A complete telegram of this many bytes with a wrong CRC.
    BadCrc(usize, u16, u16),
    /// Not a telegram start (no STX or an impossible LEN).
    NotATelegram,
}

/// Classifies the bytes at the start of `buf`.
fn head(buf: &[u8]) -> Head {
    if buf.first() != Some(&STX) {
        return Head::NotATelegram;
    }
    let [_, _, l0, l1, ..] = *buf else {
        return Head::NeedMore;
    };
    let len = usize::from(u16::from_le_bytes([l0, l1]));
    if len == 0 || len > MAX_LEN {
        return Head::NotATelegram;
    }
    let total = len + FRAME_OVERHEAD;
    if buf.len() < total {
        return Head::NeedMore;
    }
    let expected = crc16(&buf[..total - 2]);
    let found = u16::from_le_bytes([buf[total - 2], buf[total - 1]]);
    if expected == found {
        Head::Valid(total)
    } else {
        Head::BadCrc(total, expected, found)
    }
}

impl TelegramParser {
    /// A parser at stream offset 0.
    pub fn new() -> Self {
        Self::default()
    }

    /// Appends received bytes.
    pub fn push(&mut self, bytes: &[u8]) {
        self.buf.extend_from_slice(bytes);
    }

    /// Counts so far.
    pub fn stats(&self) -> ParserStats {
        self.stats
    }

    /// Bytes received but not yet turned into an event.
    pub fn pending(&self) -> usize {
        self.buf.len()
    }

    /// The next event, or `None` when more bytes are needed.
    pub fn next_event(&mut self) -> Option<Event> {
        let first = *self.buf.first()?;
        match first {
            ACK => {
                self.consume(1);
                return Some(Event::Ack);
            }
            NAK => {
                self.consume(1);
                return Some(Event::Nak);
            }
            _ => {}
        }
        match head(&self.buf) {
            Head::NeedMore => None,
            Head::Valid(total) => {
                let telegram = Telegram {
                    address: self.buf[1],
                    command: self.buf[4],
                    data: self.buf[5..total - 2].to_vec(),
                };
                self.consume(total);
                self.stats.telegrams += 1;
                Some(Event::Telegram(telegram))
            }
            Head::NotATelegram => {
                // A garbage run ends before the next byte that could start something.
                let len = 1 + self.buf[1..]
                    .iter()
                    .position(|b| matches!(*b, STX | ACK | NAK))
                    .unwrap_or(self.buf.len() - 1);
                self.stats.garbage_bytes += len as u64;
                Some(self.discard(len, DiscardKind::Garbage))
            }
            Head::BadCrc(total, expected, found) => {
                // A valid telegram starting inside this one means this one was cut short;
                // wait until any such candidate is complete before deciding.
                for p in 1..total {
                    match head(&self.buf[p..]) {
                        Head::NeedMore => return None,
                        Head::Valid(_) => {
                            self.stats.truncated += 1;
                            return Some(self.discard(p, DiscardKind::Truncated));
                        }
                        Head::BadCrc(..) | Head::NotATelegram => {}
                    }
                }
                self.stats.bad_crc += 1;
                Some(self.discard(total, DiscardKind::BadCrc { expected, found }))
            }
        }
    }

    /// The stream went quiet (a timeout, the port closed): every remaining event, with
    /// incomplete telegrams discarded as truncated so that telegrams after them are found.
    pub fn finish(&mut self) -> Vec<Event> {
        let mut out = Vec::new();
        loop {
            out.extend(std::iter::from_fn(|| self.next_event()));
            if self.buf.is_empty() {
                return out;
            }
            // The head waits for bytes that will not come: drop it up to the next STX.
            let len = 1 + self.buf[1..]
                .iter()
                .position(|b| *b == STX)
                .unwrap_or(self.buf.len() - 1);
            self.stats.truncated += 1;
            out.push(self.discard(len, DiscardKind::Truncated));
        }
    }

    fn discard(&mut self, len: usize, kind: DiscardKind) -> Event {
        let offset = self.offset;
        self.consume(len);
        Event::Discarded(Discard { offset, len, kind })
    }

    fn consume(&mut self, n: usize) {
        self.buf.drain(..n);
        self.offset += n as u64;
    }
}

#[cfg(test)]
mod tests {
    use super::super::telegram::{Mode, REPLY_MEASURED};
    use super::*;
    use proptest::prelude::*;

    fn events(parser: &mut TelegramParser) -> Vec<Event> {
        std::iter::from_fn(|| parser.next_event()).collect()
    }

    fn measured(n: u8) -> Telegram {
        Telegram::reply(REPLY_MEASURED, &[n, 0x40, 0x10, 0x02, 0x80, 0x00][..], 0x10)
    }

    #[test]
    fn telegrams_acks_and_garbage() {
        let mut p = TelegramParser::new();
        let mut bytes = vec![0xff, 0x00];
        bytes.push(ACK);
        bytes.extend(Mode::Stop.request().encode());
        bytes.extend([0x33; 3]);
        bytes.push(NAK);
        p.push(&bytes);
        let found = events(&mut p);
        assert_eq!(
            found,
            vec![
                Event::Discarded(Discard {
                    offset: 0,
                    len: 2,
                    kind: DiscardKind::Garbage
                }),
                Event::Ack,
                Event::Telegram(Mode::Stop.request()),
                Event::Discarded(Discard {
                    offset: 11,
                    len: 3,
                    kind: DiscardKind::Garbage
                }),
                Event::Nak,
            ]
        );
        assert_eq!(p.stats().garbage_bytes, 5);
    }

    #[test]
    fn byte_by_byte_equals_all_at_once() {
        let stream: Vec<u8> = [measured(1), measured(2)]
            .iter()
            .flat_map(Telegram::encode)
            .collect();
        let mut p = TelegramParser::new();
        let mut found = Vec::new();
        for b in &stream {
            p.push(std::slice::from_ref(b));
            found.extend(events(&mut p));
        }
        assert_eq!(
            found,
            vec![Event::Telegram(measured(1)), Event::Telegram(measured(2))]
        );
    }

    #[test]
    fn bad_crc_is_counted_and_the_next_telegram_found() {
        let mut bad = measured(1).encode();
        let n = bad.len();
        bad[n - 1] ^= 0xff;
        let mut p = TelegramParser::new();
        p.push(&bad);
        p.push(&measured(2).encode());
        let found = events(&mut p);
        assert!(
            matches!(found[0], Event::Discarded(Discard { offset: 0, kind: DiscardKind::BadCrc { .. }, len }) if len == n),
            "{found:?}"
        );
        assert_eq!(found[1], Event::Telegram(measured(2)));
        assert_eq!(p.stats().bad_crc, 1);
        let Event::Discarded(d) = found[0] else {
            unreachable!()
        };
        assert!(d.to_string().contains("byte offset 0"), "{d}");
    }

    #[test]
    fn truncated_telegram_then_a_valid_one() {
        let cut = &measured(1).encode()[..7];
        let mut p = TelegramParser::new();
        p.push(cut);
        p.push(&measured(2).encode());
        let found = events(&mut p);
        assert_eq!(
            found,
            vec![
                Event::Discarded(Discard {
                    offset: 0,
                    len: 7,
                    kind: DiscardKind::Truncated
                }),
                Event::Telegram(measured(2))
            ]
        );
        assert_eq!(p.stats().truncated, 1);
        // A stream that stops inside a telegram: finished as truncated.
        p.push(cut);
        assert_eq!(p.next_event(), None);
        assert_eq!(
            p.finish(),
            vec![Event::Discarded(Discard {
                offset: 7 + measured(2).encode().len() as u64,
                len: 7,
                kind: DiscardKind::Truncated
            })]
        );
        assert_eq!(p.stats().truncated, 2);
    }

    proptest! {
        /// Random noise with valid telegrams inside: no panic, every telegram found in
        /// order, and every byte accounted for.
        #[test]
        fn telegrams_survive_noise(
            chunks in proptest::collection::vec(
                (proptest::collection::vec(any::<u8>(), 0..40), proptest::collection::vec(any::<u8>(), 0..30)),
                1..12,
            ),
            split in 1usize..64,
        ) {
            let mut stream = Vec::new();
            let mut expected = Vec::new();
            for (noise, data) in &chunks {
                stream.extend(noise);
                let t = Telegram::reply(REPLY_MEASURED, data, 0x10);
                stream.extend(t.encode());
                expected.push(t);
            }
            let mut p = TelegramParser::new();
            let mut all = Vec::new();
            for piece in stream.chunks(split) {
                p.push(piece);
                all.extend(std::iter::from_fn(|| p.next_event()));
            }
            all.extend(p.finish());
            let (mut found, mut discarded, mut acks) = (Vec::new(), 0usize, 0usize);
            for e in all {
                match e {
                    Event::Telegram(t) => found.push(t),
                    Event::Discarded(d) => discarded += d.len,
                    Event::Ack | Event::Nak => acks += 1,
                }
            }
            // Noise may form telegrams of its own; ours must all be there, in order.
            let mut ours = expected.iter().peekable();
            for t in &found {
                if ours.peek() == Some(&t) { ours.next(); }
            }
            prop_assert!(ours.next().is_none(), "missing telegrams; found {:?}", found);
            let telegram_bytes: usize = found.iter().map(|t| t.encode().len()).sum();
            prop_assert_eq!(telegram_bytes + discarded + acks, stream.len());
        }

        /// Arbitrary bytes never panic and are all accounted for.
        #[test]
        fn arbitrary_bytes(bytes in proptest::collection::vec(any::<u8>(), 0..2000)) {
            let mut p = TelegramParser::new();
            p.push(&bytes);
            let n: usize = p.finish().into_iter().map(|e| match e {
                Event::Telegram(t) => t.encode().len(),
                Event::Discarded(d) => d.len,
                Event::Ack | Event::Nak => 1,
            }).sum();
            prop_assert_eq!(n, bytes.len());
        }
    }
}
