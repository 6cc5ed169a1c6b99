//! The sans-I/O half of the host side: the request frame for one read of the register
//! block (function 04, built by `rmodbus`), and a scanner that finds the reply to it in
//! whatever bytes come back — noise, echoes of the request, false starts and damaged
//! replies included. [`BaseClient`](super::BaseClient) feeds it from the line.

use super::{BaseReading, FIRST_REGISTER, REGISTER_COUNT};
use rmodbus::client::ModbusRequest;
use rmodbus::{guess_response_frame_len, ErrorKind, ModbusProto};

/// Why one poll gave no reading (counted; the caller polls again).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum PollFault {
    /// No complete reply in time.
    Timeout,
    /// The reply's CRC is wrong.
    BadCrc,
    /// The controller answered with an exception code.
    Exception(u8),
    /// The reply is not the one asked for.
    Malformed(String),
}

impl std::fmt::Display for PollFault {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            PollFault::Timeout => write!(f, "no reply to a register read (function 04)"),
            PollFault::BadCrc => write!(f, "reply with a wrong CRC"),
            PollFault::Exception(code) => write!(f, "exception reply, code {code:02x}"),
            PollFault::Malformed(what) => write!(f, "malformed reply: {what}"),
        }
    }
}

/// Finds the reply to one register read in the bytes received after the request.
///
/// RTU frames have no start byte, so the scanner resynchronises on the unit id: bytes
/// before it are noise, an exact copy of the request is the adapter's echo (RS-485
/// adapters that hear themselves), and a candidate frame that fails its checks is a
/// false start, dropped one byte at a time until a valid reply or the caller's deadline.
#[derive(Debug)]
pub struct ReplyScanner {
    unit_id: u8,
    request: ModbusRequest,
    frame: Vec<u8>,
    buf: Vec<u8>,
    /// The first candidate that failed to parse: what the poll reports if no valid reply
    /// follows.
    fault: Option<PollFault>,
    garbage_bytes: u64,
    echoes: u64,
}

impl ReplyScanner {
    /// A scanner for a read of the register block from controller `unit_id`. Fails only
    /// if `rmodbus` cannot build the request, with its reason.
    pub fn new(unit_id: u8) -> Result<Self, String> {
        let mut request = ModbusRequest::new(unit_id, ModbusProto::Rtu);
        let mut frame = Vec::new();
        request
            .generate_get_inputs(FIRST_REGISTER, REGISTER_COUNT, &mut frame)
            .map_err(|e| format!("cannot build the request: {e:?}"))?;
        Ok(Self {
            unit_id,
            request,
            frame,
            buf: Vec::new(),
            fault: None,
            garbage_bytes: 0,
            echoes: 0,
        })
    }

    /// The request to send (unit id, function 04, first register, count, CRC).
    pub fn request_frame(&self) -> &[u8] {
        &self.frame
    }

    /// Bytes so far that were not part of the reply.
    pub fn garbage_bytes(&self) -> u64 {
        self.garbage_bytes
    }

    /// Echoes of the request skipped so far.
    pub fn echoes(&self) -> u64 {
        self.echoes
    }

    /// Takes `bytes` from the line. `Some(Ok)` is the reading of a valid reply, `Some(Err)`
    /// an exception reply (valid CRC, the controller said no); `None` means the reply is
    /// not complete yet. Bytes after a reply count as garbage.
    pub fn push(&mut self, bytes: &[u8]) -> Option<Result<BaseReading, PollFault>> {
        self.buf.extend_from_slice(bytes);
        loop {
            if let Some(skip) = self.buf.iter().position(|b| *b == self.unit_id) {
                self.garbage_bytes += skip as u64;
                self.buf.drain(..skip);
            } else {
                self.garbage_bytes += self.buf.len() as u64;
                self.buf.clear();
            }
            if self.buf.starts_with(&self.frame) {
                self.echoes += 1;
                self.buf.drain(..self.frame.len());
                continue;
            }
            // A beginning of an echo waits for the rest (a reply differs by byte 2).
            if self.buf.len() < self.frame.len() && self.frame.starts_with(&self.buf) {
                return None;
            }
            match guess_response_frame_len(&self.buf, ModbusProto::Rtu) {
                Ok(len) if self.buf.len() >= usize::from(len) => {
                    let len = usize::from(len);
                    match parse_reply(&self.request, &self.buf[..len]) {
                        // A valid reply, or one with a valid CRC that says no.
                        done @ (Ok(_) | Err(PollFault::Exception(_))) => {
                            self.garbage_bytes += (self.buf.len() - len) as u64;
                            self.buf.clear();
                            return Some(done);
                        }
                        // A false start (a unit-id byte in noise) or a damaged reply.
                        Err(e) => {
                            self.fault.get_or_insert(e);
                            self.drop_first();
                        }
                    }
                }
                Ok(_) => return None,
                // Not a reply to a register read: drop this unit-id byte and look again.
                Err(_) if self.buf.len() >= 3 => self.drop_first(),
                Err(_) => return None,
            }
        }
    }

    /// The caller's deadline has passed: what is left counts as garbage, and the poll's
    /// fault is the first damaged candidate, or a timeout if there was none.
    pub fn give_up(&mut self) -> PollFault {
        self.garbage_bytes += self.buf.len() as u64;
        self.buf.clear();
        self.fault.take().unwrap_or(PollFault::Timeout)
    }

    fn drop_first(&mut self) {
        self.garbage_bytes += 1;
        self.buf.remove(0);
    }
}

/// Checks a complete reply frame (CRC, unit, function, byte count) and reads the block.
fn parse_reply(request: &ModbusRequest, frame: &[u8]) -> Result<BaseReading, PollFault> {
    match request.parse_ok(frame) {
        Ok(()) => {}
        Err(ErrorKind::FrameCRCError) => return Err(PollFault::BadCrc),
        Err(e) if e.is_modbus_error() || frame.get(1).is_some_and(|f| f & 0x80 != 0) => {
            return Err(PollFault::Exception(frame.get(2).copied().unwrap_or(0)))
        }
        Err(e) => return Err(PollFault::Malformed(format!("{e:?} in {frame:02x?}"))),
    }
    let want = 2 * usize::from(REGISTER_COUNT);
    let data = frame
        .get(3..3 + want)
        .filter(|_| frame.get(2).map(|n| usize::from(*n)) == Some(want));
    let Some(data) = data else {
        let found = frame.get(2).map_or("none".into(), |n| n.to_string());
        return Err(PollFault::Malformed(format!(
            "byte count {found} at byte offset 2, expected {want}"
        )));
    };
    let mut registers = [0u16; REGISTER_COUNT as usize];
    for (r, b) in registers.iter_mut().zip(data.chunks_exact(2)) {
        *r = u16::from_be_bytes([b[0], b[1]]);
    }
    Ok(BaseReading::from_registers(&registers))
}

#[cfg(test)]
mod tests {
    use super::super::device::{BaseController, BaseState};
    use super::*;

    const STATE: BaseState = BaseState {
        left_ticks: 0x0102_0304,
        right_ticks: 0xfffe_fffd,
        bearing_tenths: 1234,
    };

    /// What the controller latches for its first read of [`STATE`].
    const READING: BaseReading = BaseReading {
        left_ticks: 0x0102_0304,
        right_ticks: 0xfffe_fffd,
        bearing_tenths: 1234,
        counter: 1,
    };

    /// The controller's first reply, with [`STATE`].
    fn reply_bytes() -> Vec<u8> {
        let scanner = ReplyScanner::new(1).unwrap();
        let mut replies = BaseController::new(1).receive(scanner.request_frame(), STATE);
        assert_eq!(replies.len(), 1);
        replies.remove(0)
    }

    #[test]
    fn a_reply_split_anywhere_and_wrapped_in_noise_and_echoes_is_found() {
        let reply = reply_bytes();
        let request = ReplyScanner::new(1).unwrap().request_frame().to_vec();
        // Noise without the unit id, the echo, a false start (unit id then junk), the reply.
        let mut line = vec![0x55, 0xaa, 0x00];
        line.extend_from_slice(&request);
        line.extend_from_slice(&[0x01, 0x04, 0x03]);
        line.extend_from_slice(&reply);
        for split in 0..=line.len() {
            let mut scanner = ReplyScanner::new(1).unwrap();
            let first = scanner.push(&line[..split]);
            let got = first.or_else(|| scanner.push(&line[split..]));
            assert_eq!(got, Some(Ok(READING)), "split at {split}");
            assert_eq!(scanner.echoes(), 1, "split at {split}");
            assert_eq!(scanner.garbage_bytes(), 6, "split at {split}");
        }
    }

    #[test]
    fn a_wrong_crc_is_reported_when_no_valid_reply_follows() {
        let mut reply = reply_bytes();
        let last = reply.len() - 1;
        reply[last] ^= 0xff;
        let mut scanner = ReplyScanner::new(1).unwrap();
        assert_eq!(scanner.push(&reply), None);
        assert_eq!(scanner.give_up(), PollFault::BadCrc);
        assert_eq!(scanner.garbage_bytes(), reply.len() as u64);
    }

    #[test]
    fn an_exception_reply_ends_the_poll_and_nothing_is_a_timeout() {
        let mut controller = BaseController::new(1);
        controller.fail_next(0x02);
        let mut scanner = ReplyScanner::new(1).unwrap();
        let replies = controller.receive(scanner.request_frame(), STATE);
        assert_eq!(
            scanner.push(&replies[0]),
            Some(Err(PollFault::Exception(0x02)))
        );
        assert_eq!(ReplyScanner::new(1).unwrap().give_up(), PollFault::Timeout);
    }
}
