//! The controller side, for emulators: an `rmodbus` server over the register block that
//! latches the current encoder counts and bearing for every read and increments the
//! sample counter, as the dsPIC firmware does.

use super::{BaseReading, FIRST_REGISTER};
use rmodbus::server::context::ModbusContext;
use rmodbus::server::storage::ModbusStorageSmall;
use rmodbus::server::ModbusFrame;
use rmodbus::{guess_request_frame_len, ModbusProto};

/// An emulated base controller.
pub struct BaseController {
    unit_id: u8,
    storage: ModbusStorageSmall,
    counter: u16,
    pending: Vec<u8>,
    fail_next: Option<rmodbus::consts::ModbusErrorCode>,
}

/// The encoder counts and bearing the controller would latch now.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct BaseState {
    /// Left encoder count.
    pub left_ticks: u32,
    /// Right encoder count.
    pub right_ticks: u32,
    /// Compass bearing (tenths of a degree).
    pub bearing_tenths: u16,
}

impl BaseController {
    /// A controller answering as `unit_id`.
    pub fn new(unit_id: u8) -> Self {
        Self {
            unit_id,
            storage: ModbusStorageSmall::new(),
            counter: 0,
            pending: Vec::new(),
            fail_next: None,
        }
    }

    /// Takes bytes from the host; for each complete request, latches `state` and
    /// returns the reply frames (empty for requests to other units). Bytes that cannot
    /// start a request are dropped.
    pub fn receive(&mut self, bytes: &[u8], state: BaseState) -> Vec<Vec<u8>> {
        self.pending.extend_from_slice(bytes);
        let mut replies = Vec::new();
        while !self.pending.is_empty() {
            let len = match guess_request_frame_len(&self.pending, ModbusProto::Rtu) {
                Ok(len) => usize::from(len),
                Err(rmodbus::ErrorKind::OOB) => break,
                Err(_) => {
                    self.pending.remove(0);
                    continue;
                }
            };
            if self.pending.len() < len {
                break;
            }
            let frame: Vec<u8> = self.pending.drain(..len).collect();
            if let Some(reply) = self.answer(&frame, state) {
                replies.push(reply);
            }
        }
        replies
    }

    /// Makes the next reply an exception reply with `code` (fault injection; 0x04 is
    /// "slave device failure").
    pub fn fail_next(&mut self, code: u8) {
        self.fail_next = rmodbus::ErrorKind::from_modbus_error(code)
            .to_modbus_error()
            .ok();
    }

    fn answer(&mut self, frame: &[u8], state: BaseState) -> Option<Vec<u8>> {
        self.counter = self.counter.wrapping_add(1);
        let reading = BaseReading {
            left_ticks: state.left_ticks,
            right_ticks: state.right_ticks,
            bearing_tenths: state.bearing_tenths,
            counter: self.counter,
        };
        for (i, value) in reading.to_registers().into_iter().enumerate() {
            self.storage
                .set_input(FIRST_REGISTER + i as u16, value)
                .ok()?;
        }
        let mut response = Vec::new();
        let mut f = ModbusFrame::new(self.unit_id, frame, ModbusProto::Rtu, &mut response);
        f.parse().ok()?;
        if let Some(code) = self.fail_next.take() {
            f.error = Some(code);
        } else if f.processing_required {
            if f.readonly {
                f.process_read(&self.storage).ok()?;
            } else {
                // The block is read-only: writes get "illegal function".
                f.error = Some(rmodbus::consts::ModbusErrorCode::IllegalFunction);
            }
        }
        if !f.response_required {
            return None;
        }
        f.finalize_response().ok()?;
        Some(response)
    }
}

#[cfg(test)]
mod tests {
    use super::super::{BaseClient, BaseConfig, PollFault};
    use super::*;
    use crate::devices::Link;
    use std::collections::VecDeque;
    use std::io;

    /// What the wire does to the reply of each request, in order.
    #[derive(Clone, Copy, PartialEq)]
    enum Reply {
        Normal,
        Exception,
        Corrupt,
    }

    /// The client wired straight to an emulated controller.
    struct Wire {
        controller: BaseController,
        state: BaseState,
        to_host: VecDeque<u8>,
        plan: VecDeque<Reply>,
        /// The adapter echoes what the host sends (RS-485).
        echo: bool,
        /// Bytes on the line before each reply.
        noise: Vec<u8>,
        /// A pause before the next read returns.
        slow_read: Option<std::time::Duration>,
    }

    impl Link for Wire {
        fn read_some(&mut self, buf: &mut [u8]) -> io::Result<usize> {
            if let Some(pause) = self.slow_read.take() {
                // A host busy elsewhere: it reads the reply late.
                std::thread::sleep(pause);
            }
            let n = buf.len().min(self.to_host.len());
            for (b, v) in buf.iter_mut().zip(self.to_host.drain(..n)) {
                *b = v;
            }
            Ok(n)
        }
        fn write_all_bytes(&mut self, bytes: &[u8]) -> io::Result<()> {
            let plan = self.plan.pop_front().unwrap_or(Reply::Normal);
            if self.echo {
                self.to_host.extend(bytes);
            }
            self.to_host.extend(self.noise.iter().copied());
            if plan == Reply::Exception {
                self.controller.fail_next(0x04);
            }
            for mut reply in self.controller.receive(bytes, self.state) {
                if plan == Reply::Corrupt {
                    reply[4] ^= 0x10;
                }
                self.to_host.extend(reply);
            }
            Ok(())
        }
        fn set_baud_rate(&mut self, _: u32) -> io::Result<()> {
            Ok(())
        }
        fn clear_input(&mut self) -> io::Result<()> {
            self.to_host.clear();
            Ok(())
        }
        fn name(&self) -> &str {
            "wire"
        }
    }

    #[test]
    fn polls_read_the_block_and_faults_are_counted() {
        let wire = Wire {
            controller: BaseController::new(1),
            state: BaseState {
                left_ticks: 70_000,
                right_ticks: u32::MAX,
                bearing_tenths: 1234,
            },
            to_host: VecDeque::new(),
            plan: VecDeque::from([Reply::Normal, Reply::Exception, Reply::Corrupt]),
            echo: false,
            noise: Vec::new(),
            slow_read: None,
        };
        let config = BaseConfig {
            reply_timeout: std::time::Duration::from_millis(20),
            ..BaseConfig::default()
        };
        let mut client = BaseClient::new(wire, config);
        let r = client.poll().unwrap().unwrap();
        assert_eq!(
            (r.left_ticks, r.right_ticks, r.bearing_tenths, r.counter),
            (70_000, u32::MAX, 1234, 1)
        );
        assert_eq!(client.poll().unwrap(), None);
        assert_eq!(client.last_fault(), Some(&PollFault::Exception(0x04)));
        assert_eq!(client.poll().unwrap(), None);
        assert_eq!(client.last_fault(), Some(&PollFault::BadCrc));
        // The controller latched three samples; this read is its fourth.
        assert_eq!(client.poll().unwrap().unwrap().counter, 4);
        let c = client.counters();
        assert_eq!((c.polls, c.replies, c.exceptions, c.bad_crc), (4, 2, 1, 1));
    }

    #[test]
    fn echoes_and_false_starts_do_not_cost_the_reply() {
        // An adapter that echoes the request, then noise holding a false start: unit 1,
        // function 04, byte count 2 and two bytes of "CRC" - a 7-byte frame that fails.
        let wire = Wire {
            controller: BaseController::new(1),
            state: BaseState {
                left_ticks: 12,
                right_ticks: 34,
                bearing_tenths: 56,
            },
            to_host: VecDeque::new(),
            plan: VecDeque::from([Reply::Normal, Reply::Corrupt]),
            echo: true,
            noise: vec![0x55, 0x01, 0x04, 0x02, 0xaa, 0xbb, 0xcc, 0xdd],
            slow_read: None,
        };
        let config = BaseConfig {
            reply_timeout: std::time::Duration::from_millis(20),
            ..BaseConfig::default()
        };
        let mut client = BaseClient::new(wire, config);
        let r = client.poll().unwrap().unwrap();
        assert_eq!(
            (r.left_ticks, r.right_ticks, r.bearing_tenths),
            (12, 34, 56)
        );
        // A damaged reply after the same noise is still reported as such.
        assert_eq!(client.poll().unwrap(), None);
        assert_eq!(client.last_fault(), Some(&PollFault::BadCrc));
        let c = client.counters();
        assert_eq!((c.replies, c.echoes, c.bad_crc), (1, 2, 1), "{c:?}");
        assert!(c.garbage_bytes >= 16, "{c:?}");
    }

    #[test]
    fn a_sample_is_timed_by_its_request_not_by_a_late_read_of_the_reply() {
        use std::time::{Duration, Instant};
        let pause = Duration::from_millis(30);
        let wire = Wire {
            controller: BaseController::new(1),
            state: BaseState {
                left_ticks: 1,
                right_ticks: 2,
                bearing_tenths: 3,
            },
            to_host: VecDeque::new(),
            plan: VecDeque::new(),
            echo: false,
            noise: Vec::new(),
            slow_read: Some(pause),
        };
        let config = BaseConfig {
            reply_timeout: Duration::from_millis(200),
            ..BaseConfig::default()
        };
        let mut client = BaseClient::new(wire, config);
        let before = Instant::now();
        assert!(client.poll().unwrap().is_some());
        let read = Instant::now();
        let requested = client.last_request();
        assert!(requested >= before);
        // The reply was read at least the pause after the request went out.
        assert!(read - requested >= pause, "{:?}", read - requested);
    }
}
