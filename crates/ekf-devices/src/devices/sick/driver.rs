//! The host side of an LMS 2xx: find the scanner's baud rate (9600 after power-up), switch
//! to the configured rate (38400, or 500k where the adapter allows), set angle and
//! resolution, start continuous output, read scans, stop output on exit.

use super::measured::MeasuredValues;
use super::parser::{DiscardKind, Event, ParserStats, TelegramParser};
use super::telegram::{
    BaudRate, Mode, Telegram, Variant, FRAME_OVERHEAD, REPLY_MEASURED, REPLY_MODE, REPLY_VARIANT,
};
use crate::devices::arrival_clock::ArrivalClock;
use crate::devices::{DeviceError, Link};
use std::time::{Duration, Instant};

const DEVICE: &str = "laser";

/// How the scanner is set up.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SickConfig {
    /// The rate to run at: 38400, or 500000 (falls back to 38400 if the adapter cannot).
    pub baud: BaudRate,
    /// Angular range and resolution.
    pub variant: Variant,
    /// How long to wait for the reply to a request.
    pub reply_timeout: Duration,
    /// How long without a valid scan before the scanner counts as silent.
    pub scan_timeout: Duration,
}

impl Default for SickConfig {
    fn default() -> Self {
        Self {
            baud: BaudRate::B38400,
            variant: Variant::DEFAULT,
            reply_timeout: Duration::from_millis(500),
            scan_timeout: Duration::from_secs(2),
        }
    }
}

/// What the driver has counted, for diagnostics.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct SickCounters {
    /// The stream parser's counts (telegrams, garbage bytes, bad CRCs, truncations).
    #[serde(flatten)]
    pub parser: ParserStats,
    /// Scans delivered.
    pub scans: u64,
    /// `B0` telegrams with a valid CRC that could not be decoded (units, counts).
    pub bad_scans: u64,
    /// NAKs received.
    pub naks: u64,
}

/// One scan, with when it was measured.
#[derive(Debug, Clone, PartialEq)]
pub struct Scan {
    /// The values as the scanner sent them.
    pub values: MeasuredValues,
    /// When the telegram's last byte arrived: the read that brought it, less the time of
    /// the bytes that came after it in the same reads, then put on the send grid of the
    /// continuous output ([`ArrivalClock`]) so that a read the host made late does not
    /// make the scan late.
    pub received: Instant,
    /// When the scan was measured: [`Self::received`] less the telegram's time on the line
    /// (bytes · 10 / baud) and half the sweep ([`Variant::sweep_duration`]), so the middle
    /// of the sweep. The scanner sends a scan as soon as it is complete.
    pub measured: Instant,
}

/// A connected, continuously scanning LMS 2xx.
pub struct SickLaser<L: Link> {
    link: L,
    parser: TelegramParser,
    config: SickConfig,
    baud: BaudRate,
    counters: SickCounters,
    last_fault: Option<String>,
    /// When the last read that brought bytes returned.
    last_read: Instant,
    /// Times the telegrams of the continuous output on their send grid.
    clock: ArrivalClock,
}

impl<L: Link> SickLaser<L> {
    /// Finds the scanner, configures it and starts continuous output.
    pub fn connect(link: L, config: SickConfig) -> Result<Self, DeviceError> {
        let mut laser = Self {
            link,
            parser: TelegramParser::new(),
            config,
            baud: BaudRate::B9600,
            counters: SickCounters::default(),
            last_fault: None,
            last_read: Instant::now(),
            clock: ArrivalClock::new(),
        };
        laser.find_baud_rate()?;
        laser.switch_baud_rate()?;
        laser.set_variant()?;
        laser.set_mode(Mode::Continuous)?;
        Ok(laser)
    }

    /// The baud rate in use.
    pub fn baud_rate(&self) -> BaudRate {
        self.baud
    }

    /// The configured variant (angle and resolution).
    pub fn variant(&self) -> Variant {
        self.config.variant
    }

    /// Counts so far.
    pub fn counters(&self) -> SickCounters {
        SickCounters {
            parser: self.parser.stats(),
            ..self.counters
        }
    }

    /// The most recent discarded input or bad scan, described.
    pub fn last_fault(&self) -> Option<&str> {
        self.last_fault.as_deref()
    }

    /// The port's path.
    pub fn port(&self) -> &str {
        self.link.name()
    }

    /// The time from a scan's measurement (the middle of its sweep) to the arrival of its
    /// telegram's last byte at the rate in use.
    pub fn latency(&self) -> Duration {
        self.baud
            .transmission_time(self.config.variant.telegram_bytes())
            + self.config.variant.sweep_duration() / 2
    }

    /// The next valid scan. Garbage, bad CRCs, truncated telegrams and undecodable scans
    /// are counted and skipped; no valid scan within the scan timeout is an error.
    pub fn next_scan(&mut self) -> Result<Scan, DeviceError> {
        let deadline = Instant::now() + self.config.scan_timeout;
        loop {
            while let Some(event) = self.parser.next_event() {
                if let Some(scan) = self.scan_event(event) {
                    return Ok(scan);
                }
            }
            if Instant::now() >= deadline {
                for event in self.parser.finish() {
                    self.note(&event);
                }
                return Err(self.link.silent(
                    DEVICE,
                    self.config.scan_timeout,
                    "measured values (B0 telegrams) in continuous output".into(),
                ));
            }
            self.read()?;
        }
    }

    /// Stops continuous output (`20 25`), as on exit, and returns the link.
    pub fn stop(mut self) -> Result<L, DeviceError> {
        self.set_mode(Mode::Stop)?;
        Ok(self.link)
    }

    fn scan_event(&mut self, event: Event) -> Option<Scan> {
        let Event::Telegram(t) = &event else {
            self.note(&event);
            return None;
        };
        if t.command != REPLY_MEASURED {
            return None;
        }
        let decoded = MeasuredValues::decode(t.payload())
            .and_then(|m| m.check_count(self.config.variant).map(|()| m));
        match decoded {
            Ok(values) => {
                self.counters.scans += 1;
                // The bytes still in the parser came after this telegram's last byte.
                let after = self.baud.byte_time() * self.parser.pending() as u32;
                let read = self.last_read.checked_sub(after).unwrap_or(self.last_read);
                let received = self.clock.time_of(read);
                let on_line = self
                    .baud
                    .transmission_time(t.data.len() + 1 + FRAME_OVERHEAD);
                let before = on_line + self.config.variant.sweep_duration() / 2;
                Some(Scan {
                    values,
                    received,
                    measured: received.checked_sub(before).unwrap_or(received),
                })
            }
            Err(e) => {
                self.counters.bad_scans += 1;
                self.last_fault = Some(e.to_string());
                None
            }
        }
    }

    fn note(&mut self, event: &Event) {
        match event {
            Event::Discarded(d) => self.last_fault = Some(d.to_string()),
            Event::Nak => self.counters.naks += 1,
            Event::Telegram(_) | Event::Ack => {}
        }
    }

    /// Tries the rates in [`BaudRate::SEARCH_ORDER`] until the scanner answers a stop
    /// request; stopping first also quiets a scanner still streaming from a past run.
    fn find_baud_rate(&mut self) -> Result<(), DeviceError> {
        for baud in BaudRate::SEARCH_ORDER {
            self.set_host_baud(baud)?;
            match self.set_mode(Mode::Stop) {
                Ok(()) => return Ok(()),
                Err(DeviceError::Silent { .. }) => continue,
                Err(e) => return Err(e),
            }
        }
        Err(self.link.silent(
            DEVICE,
            self.config.reply_timeout * BaudRate::SEARCH_ORDER.len() as u32,
            "an ACK (06) and an A0 reply to the stop request 02 00 02 00 20 25 at 9600, \
             38400, 500000 or 19200 baud: is the scanner powered and connected?"
                .into(),
        ))
    }

    /// Switches to the configured rate; 500k falls back to 38400 when the adapter
    /// refuses that rate.
    fn switch_baud_rate(&mut self) -> Result<(), DeviceError> {
        let mut target = self.config.baud;
        if target == self.baud {
            return Ok(());
        }
        if self.link.set_baud_rate(target.bits_per_second()).is_err() {
            self.last_fault = Some(format!(
                "the adapter cannot run at {} baud; using 38400",
                target.bits_per_second()
            ));
            target = BaudRate::B38400;
        }
        self.set_host_baud(self.baud)?;
        self.set_mode(Mode::Baud(target))?;
        self.set_host_baud(target)
    }

    fn set_variant(&mut self) -> Result<(), DeviceError> {
        let v = self.config.variant;
        let reply = self.transact(&v.request(), REPLY_VARIANT)?;
        let payload = reply.payload();
        let echoed = payload.get(1..).and_then(Variant::from_bytes);
        if payload.first() != Some(&1) || echoed != Some(v) {
            return Err(self.link.refused(
                DEVICE,
                format!(
                    "refused angle {}° at resolution {}° (3B reply {:02x?})",
                    v.angle_deg,
                    f64::from(v.resolution_cdeg) / 100.0,
                    reply.data
                ),
            ));
        }
        Ok(())
    }

    fn set_mode(&mut self, mode: Mode) -> Result<(), DeviceError> {
        let reply = self.transact(&mode.request(), REPLY_MODE)?;
        match reply.payload().first() {
            Some(0) => Ok(()),
            other => Err(self.link.refused(
                DEVICE,
                format!(
                    "mode change 20 {:02x} failed (A0 status {other:02x?}, expected 00)",
                    mode.code()
                ),
            )),
        }
    }

    /// Sends `request` and waits for the reply `reply_command`, skipping other telegrams
    /// (scans still in flight). A NAK is a refusal. When the line goes quiet (a read
    /// slice without bytes: many byte times) with bytes still waiting - the head of a
    /// telegram that will not be completed, or an STX in range data with a bogus length -
    /// they are flushed, so a reply behind them is not lost.
    fn transact(&mut self, request: &Telegram, reply_command: u8) -> Result<Telegram, DeviceError> {
        let bytes = request.encode();
        self.link
            .write_all_bytes(&bytes)
            .map_err(|source| self.link.io_error(DEVICE, "writing a request", source))?;
        let deadline = Instant::now() + self.config.reply_timeout;
        loop {
            while let Some(event) = self.parser.next_event() {
                if let Some(reply) = self.awaited(event, reply_command, &bytes) {
                    return reply;
                }
            }
            let quiet = Instant::now() >= deadline || self.read()? == 0;
            if quiet && self.parser.pending() > 0 {
                for event in self.parser.finish() {
                    if let Some(reply) = self.awaited(event, reply_command, &bytes) {
                        return reply;
                    }
                }
            }
            if Instant::now() >= deadline {
                return Err(self.link.silent(
                    DEVICE,
                    self.config.reply_timeout,
                    format!(
                        "an {reply_command:02X} reply to {:02x?} at {} baud",
                        bytes,
                        self.baud.bits_per_second()
                    ),
                ));
            }
        }
    }

    /// What an event means while waiting for `reply_command` to `request`: the reply,
    /// a refusal (NAK), or nothing (noted).
    fn awaited(
        &mut self,
        event: Event,
        reply_command: u8,
        request: &[u8],
    ) -> Option<Result<Telegram, DeviceError>> {
        match event {
            Event::Telegram(t) if t.command == reply_command => Some(Ok(t)),
            Event::Nak => {
                self.counters.naks += 1;
                Some(Err(self.link.refused(
                    DEVICE,
                    format!("NAK (15) to the request {request:02x?}"),
                )))
            }
            other => {
                self.note(&other);
                None
            }
        }
    }

    fn set_host_baud(&mut self, baud: BaudRate) -> Result<(), DeviceError> {
        self.link
            .set_baud_rate(baud.bits_per_second())
            .map_err(|source| self.link.io_error(DEVICE, "setting the baud rate", source))?;
        self.baud = baud;
        // Bytes received at another rate are noise; start clean.
        self.link
            .clear_input()
            .map_err(|source| self.link.io_error(DEVICE, "clearing the input", source))?;
        for event in self.parser.finish() {
            if let Event::Discarded(d) = event {
                if d.kind == DiscardKind::Garbage {
                    self.last_fault = Some(d.to_string());
                }
            }
        }
        Ok(())
    }

    /// Reads what is there (waiting at most a read slice); the number of bytes.
    fn read(&mut self) -> Result<usize, DeviceError> {
        let mut buf = [0u8; 1024];
        let n = self
            .link
            .read_some(&mut buf)
            .map_err(|source| self.link.io_error(DEVICE, "reading", source))?;
        if n > 0 {
            self.last_read = Instant::now();
        }
        self.parser.push(&buf[..n]);
        Ok(n)
    }
}
