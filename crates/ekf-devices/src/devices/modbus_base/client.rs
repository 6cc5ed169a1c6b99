//! The host side: reads the register block with one MODBUS RTU request (function 04,
//! built and checked by `rmodbus`). Bad CRCs, exception replies, garbage and missing
//! replies are counted and never returned as readings; a controller that gives no valid
//! reply for the silence timeout is an error naming the port.

use super::{BaseReading, FIRST_REGISTER, REGISTER_COUNT};
use crate::devices::{DeviceError, Link};
use rmodbus::client::ModbusRequest;
use rmodbus::{guess_response_frame_len, ErrorKind, ModbusProto};
use std::time::{Duration, Instant};

const DEVICE: &str = "base";

/// How the controller is reached.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BaseConfig {
    /// MODBUS unit id of the controller.
    pub unit_id: u8,
    /// How long to wait for one reply.
    pub reply_timeout: Duration,
    /// How long without a valid reply before the controller counts as silent.
    pub silence_timeout: Duration,
}

impl Default for BaseConfig {
    fn default() -> Self {
        Self {
            unit_id: 1,
            reply_timeout: Duration::from_millis(80),
            silence_timeout: Duration::from_secs(2),
        }
    }
}

/// What the client has counted, for diagnostics.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct BaseCounters {
    /// Polls sent.
    pub polls: u64,
    /// Valid replies.
    pub replies: u64,
    /// Polls without a complete reply in time.
    pub timeouts: u64,
    /// Replies with a wrong CRC.
    pub bad_crc: u64,
    /// Exception replies (function 0x84).
    pub exceptions: u64,
    /// Bytes that were not part of a reply.
    pub garbage_bytes: u64,
    /// Echoes of our own request skipped (RS-485 adapters that hear themselves).
    pub echoes: u64,
}

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

/// A register read request's time on the line, in characters: its 8 bytes and the 3.5
/// characters of silence that end an RTU frame (MODBUS over serial line, §2.5.1.1).
pub const REQUEST_CHARACTERS: f64 = 8.0 + 3.5;

/// The polling client.
pub struct BaseClient<L: Link> {
    link: L,
    config: BaseConfig,
    counters: BaseCounters,
    last_valid: Instant,
    last_fault: Option<PollFault>,
    /// When the last request was handed to the line.
    last_request: Instant,
}

impl<L: Link> BaseClient<L> {
    /// A client on `link`.
    pub fn new(link: L, config: BaseConfig) -> Self {
        Self {
            link,
            config,
            counters: BaseCounters::default(),
            last_valid: Instant::now(),
            last_fault: None,
            last_request: Instant::now(),
        }
    }

    /// When the last request was handed to the line. The controller latches the sample
    /// it answers with when the request has arrived, a request's time on the line later
    /// ([`REQUEST_CHARACTERS`]); unlike the reply's arrival, this does not move when the
    /// host is slow to read the reply.
    pub fn last_request(&self) -> Instant {
        self.last_request
    }

    /// Counts so far.
    pub fn counters(&self) -> BaseCounters {
        self.counters
    }

    /// The most recent fault.
    pub fn last_fault(&self) -> Option<&PollFault> {
        self.last_fault.as_ref()
    }

    /// The port's path.
    pub fn port(&self) -> &str {
        self.link.name()
    }

    /// One poll: `Ok(Some)` a valid reading, `Ok(None)` a counted fault, `Err` when the
    /// line failed or no valid reply came for the silence timeout.
    pub fn poll(&mut self) -> Result<Option<BaseReading>, DeviceError> {
        match self.read_block()? {
            Ok(reading) => {
                self.counters.replies += 1;
                self.last_valid = Instant::now();
                Ok(Some(reading))
            }
            Err(fault) => {
                match fault {
                    PollFault::Timeout => self.counters.timeouts += 1,
                    PollFault::BadCrc => self.counters.bad_crc += 1,
                    PollFault::Exception(_) => self.counters.exceptions += 1,
                    PollFault::Malformed(_) => {}
                }
                let waited = self.last_valid.elapsed();
                if waited >= self.config.silence_timeout {
                    return Err(DeviceError::Silent {
                        device: DEVICE,
                        port: self.link.name().into(),
                        waited,
                        expected: format!(
                            "a MODBUS RTU reply from unit {} to a read of input registers {}..{} (last problem: {fault})",
                            self.config.unit_id,
                            FIRST_REGISTER,
                            FIRST_REGISTER + REGISTER_COUNT - 1
                        ),
                    });
                }
                self.last_fault = Some(fault);
                Ok(None)
            }
        }
    }

    fn read_block(&mut self) -> Result<Result<BaseReading, PollFault>, DeviceError> {
        let mut request = ModbusRequest::new(self.config.unit_id, ModbusProto::Rtu);
        let mut frame = Vec::new();
        request
            .generate_get_inputs(FIRST_REGISTER, REGISTER_COUNT, &mut frame)
            .map_err(|e| {
                self.link
                    .refused(DEVICE, format!("cannot build the request: {e:?}"))
            })?;
        // A late reply to an earlier poll must not be taken for this one.
        self.link
            .clear_input()
            .map_err(|source| self.link.io_error(DEVICE, "clearing the input", source))?;
        self.last_request = Instant::now();
        self.link
            .write_all_bytes(&frame)
            .map_err(|source| self.link.io_error(DEVICE, "writing a request", source))?;
        self.counters.polls += 1;
        let deadline = Instant::now() + self.config.reply_timeout;
        let mut buf: Vec<u8> = Vec::new();
        // The first candidate that failed to parse: what the poll reports if no valid
        // reply follows.
        let mut fault = None;
        loop {
            // Resynchronise on the unit id: RTU has no start byte.
            if let Some(skip) = buf.iter().position(|b| *b == self.config.unit_id) {
                self.counters.garbage_bytes += skip as u64;
                buf.drain(..skip);
            } else {
                self.counters.garbage_bytes += buf.len() as u64;
                buf.clear();
            }
            if buf.starts_with(&frame) {
                // Our own request, echoed by the adapter.
                self.counters.echoes += 1;
                buf.drain(..frame.len());
                continue;
            }
            // A beginning of an echo waits for the rest (a reply differs by byte 2).
            let echo_so_far = buf.len() < frame.len() && frame.starts_with(&buf);
            match guess_response_frame_len(&buf, ModbusProto::Rtu) {
                _ if echo_so_far => {}
                Ok(len) if buf.len() >= usize::from(len) => {
                    let len = usize::from(len);
                    match parse_reply(&request, &buf[..len]) {
                        Ok(reading) => {
                            self.counters.garbage_bytes += (buf.len() - len) as u64;
                            return Ok(Ok(reading));
                        }
                        // A reply with a valid CRC that says no.
                        Err(e @ PollFault::Exception(_)) => {
                            self.counters.garbage_bytes += (buf.len() - len) as u64;
                            return Ok(Err(e));
                        }
                        // A false start (a unit-id byte in noise) or a damaged reply:
                        // drop one byte and look on for a valid reply until the deadline.
                        Err(e) => {
                            fault.get_or_insert(e);
                            self.counters.garbage_bytes += 1;
                            buf.remove(0);
                            continue;
                        }
                    }
                }
                Ok(_) => {}
                Err(_) if buf.len() >= 3 => {
                    // Not a reply to a register read: drop this unit-id byte and look again.
                    self.counters.garbage_bytes += 1;
                    buf.remove(0);
                    continue;
                }
                Err(_) => {}
            }
            if Instant::now() >= deadline {
                self.counters.garbage_bytes += buf.len() as u64;
                return Ok(Err(fault.unwrap_or(PollFault::Timeout)));
            }
            let mut chunk = [0u8; 256];
            let n = self
                .link
                .read_some(&mut chunk)
                .map_err(|source| self.link.io_error(DEVICE, "reading", source))?;
            buf.extend_from_slice(&chunk[..n]);
        }
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
        .filter(|_| usize::from(frame[2]) == want);
    let Some(data) = data else {
        return Err(PollFault::Malformed(format!(
            "byte count {} at byte offset 2, expected {want}",
            frame[2]
        )));
    };
    let mut registers = [0u16; REGISTER_COUNT as usize];
    for (r, b) in registers.iter_mut().zip(data.chunks_exact(2)) {
        *r = u16::from_be_bytes([b[0], b[1]]);
    }
    Ok(BaseReading::from_registers(&registers))
}
