//! The host side: reads the register block with one MODBUS RTU request (function 04,
//! built and checked by `rmodbus`). Bad CRCs, exception replies, garbage and missing
//! replies are counted and never returned as readings; a controller that gives no valid
//! reply for the silence timeout is an error naming the port.

use super::reply::{PollFault, ReplyScanner};
use super::{BaseReading, FIRST_REGISTER, REGISTER_COUNT};
use crate::devices::{DeviceError, Link};
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
        let mut scanner = ReplyScanner::new(self.config.unit_id)
            .map_err(|message| self.link.refused(DEVICE, message))?;
        // A late reply to an earlier poll must not be taken for this one.
        self.link
            .clear_input()
            .map_err(|source| self.link.io_error(DEVICE, "clearing the input", source))?;
        self.last_request = Instant::now();
        self.link
            .write_all_bytes(scanner.request_frame())
            .map_err(|source| self.link.io_error(DEVICE, "writing a request", source))?;
        self.counters.polls += 1;
        let deadline = Instant::now() + self.config.reply_timeout;
        let outcome = loop {
            if Instant::now() >= deadline {
                break Ok(Err(scanner.give_up()));
            }
            let mut chunk = [0u8; 256];
            match self.link.read_some(&mut chunk) {
                Ok(n) => {
                    if let Some(outcome) = scanner.push(&chunk[..n]) {
                        break Ok(outcome);
                    }
                }
                Err(source) => break Err(self.link.io_error(DEVICE, "reading", source)),
            }
        };
        // Counted whatever ended the poll, a failed read included.
        self.counters.garbage_bytes += scanner.garbage_bytes();
        self.counters.echoes += scanner.echoes();
        outcome
    }
}
