//! LMS 2xx telegrams: `STX ADR LEN(u16 LE) CMD DATA… [STATUS] CRC(u16 LE)`, the requests
//! the host sends and the replies it reads (docs/ARCHITECTURE.md §5).

use super::crc::crc16;
use std::time::Duration;

/// Start of every telegram.
pub const STX: u8 = 0x02;
/// Acknowledge byte the scanner sends before its reply.
pub const ACK: u8 = 0x06;
/// Not-acknowledge byte: the scanner refused the request.
pub const NAK: u8 = 0x15;
/// Address byte of host → scanner telegrams.
pub const HOST_ADDRESS: u8 = 0x00;
/// Address byte of scanner → host telegrams.
pub const REPLY_ADDRESS: u8 = 0x80;
/// Largest LEN (CMD through STATUS) an LMS 2xx sends: 812 bytes.
pub const MAX_LEN: usize = 812;
/// Bytes around the LEN-counted part: STX, ADR, two LEN bytes, two CRC bytes.
pub const FRAME_OVERHEAD: usize = 6;

/// Mode-change command (`20 mm`).
pub const CMD_MODE: u8 = 0x20;
/// Reply to a mode change.
pub const REPLY_MODE: u8 = 0xA0;
/// Set angular range and resolution (`3B`).
pub const CMD_VARIANT: u8 = 0x3B;
/// Reply to a variant change.
pub const REPLY_VARIANT: u8 = 0xBB;
/// Measured values, sent continuously after `20 24`.
pub const REPLY_MEASURED: u8 = 0xB0;

/// One telegram: address, command and the bytes between CMD and the CRC (for replies the
/// last of them is the STATUS byte).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Telegram {
    /// `0x00` from the host, `0x80` from the scanner.
    pub address: u8,
    /// The command (requests) or request command + 0x80 (replies).
    pub command: u8,
    /// Data after CMD, including the STATUS byte of replies.
    pub data: Vec<u8>,
}

impl Telegram {
    /// A host → scanner telegram.
    pub fn request(command: u8, data: &[u8]) -> Self {
        Self {
            address: HOST_ADDRESS,
            command,
            data: data.to_vec(),
        }
    }

    /// A scanner → host telegram with `status` appended to `data`.
    pub fn reply(command: u8, data: &[u8], status: u8) -> Self {
        let mut bytes = data.to_vec();
        bytes.push(status);
        Self {
            address: REPLY_ADDRESS,
            command,
            data: bytes,
        }
    }

    /// The telegram on the wire, CRC included. `data` longer than [`MAX_LEN`] − 1 makes
    /// a telegram no scanner accepts; LEN is then still written modulo 2¹⁶.
    pub fn encode(&self) -> Vec<u8> {
        let len = (self.data.len() + 1) as u16;
        let mut out = Vec::with_capacity(self.data.len() + FRAME_OVERHEAD + 1);
        out.extend_from_slice(&[STX, self.address]);
        out.extend_from_slice(&len.to_le_bytes());
        out.push(self.command);
        out.extend_from_slice(&self.data);
        let crc = crc16(&out);
        out.extend_from_slice(&crc.to_le_bytes());
        out
    }

    /// The reply's STATUS byte (the last data byte), if it has one.
    pub fn status(&self) -> Option<u8> {
        self.data.last().copied()
    }

    /// The reply's data without its STATUS byte.
    pub fn payload(&self) -> &[u8] {
        &self.data[..self.data.len().saturating_sub(1)]
    }
}

/// Operating modes and baud rates selected with `20 mm`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// `24`: send measured values continuously.
    Continuous,
    /// `25`: stop continuous output (values only on request).
    Stop,
    /// `40`/`41`/`42`/`48`: switch to this baud rate.
    Baud(BaudRate),
}

/// The baud rates an LMS 2xx speaks.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BaudRate {
    /// 9600 baud, the power-up rate.
    B9600,
    /// 19200 baud.
    B19200,
    /// 38400 baud.
    B38400,
    /// 500 000 baud (RS-422 adapters only).
    B500000,
}

impl BaudRate {
    /// Every rate, the power-up rate first, then in the order a lost scanner is searched.
    pub const SEARCH_ORDER: [BaudRate; 4] = [
        BaudRate::B9600,
        BaudRate::B38400,
        BaudRate::B500000,
        BaudRate::B19200,
    ];

    /// Bits per second.
    pub fn bits_per_second(self) -> u32 {
        match self {
            BaudRate::B9600 => 9600,
            BaudRate::B19200 => 19_200,
            BaudRate::B38400 => 38_400,
            BaudRate::B500000 => 500_000,
        }
    }

    /// Time one byte takes on the line: 10 bits (start, 8 data, stop).
    pub fn byte_time(self) -> Duration {
        Duration::from_nanos(10_000_000_000 / u64::from(self.bits_per_second()))
    }

    /// Time `bytes` bytes take on the line.
    pub fn transmission_time(self, bytes: usize) -> Duration {
        Duration::from_nanos(
            (bytes as u64).saturating_mul(10_000_000_000) / u64::from(self.bits_per_second()),
        )
    }

    /// The rate with this many bits per second, if an LMS 2xx has it.
    pub fn from_bits_per_second(bps: u32) -> Option<Self> {
        Self::SEARCH_ORDER
            .into_iter()
            .find(|b| b.bits_per_second() == bps)
    }
}

impl Mode {
    /// The mode byte after `20`.
    pub fn code(self) -> u8 {
        match self {
            Mode::Continuous => 0x24,
            Mode::Stop => 0x25,
            Mode::Baud(BaudRate::B38400) => 0x40,
            Mode::Baud(BaudRate::B19200) => 0x41,
            Mode::Baud(BaudRate::B9600) => 0x42,
            Mode::Baud(BaudRate::B500000) => 0x48,
        }
    }

    /// The mode a mode byte selects.
    pub fn from_code(code: u8) -> Option<Self> {
        Some(match code {
            0x24 => Mode::Continuous,
            0x25 => Mode::Stop,
            0x40 => Mode::Baud(BaudRate::B38400),
            0x41 => Mode::Baud(BaudRate::B19200),
            0x42 => Mode::Baud(BaudRate::B9600),
            0x48 => Mode::Baud(BaudRate::B500000),
            _ => return None,
        })
    }

    /// The request telegram `20 mm`.
    pub fn request(self) -> Telegram {
        Telegram::request(CMD_MODE, &[self.code()])
    }
}

/// One turn of an LMS 2xx's mirror: it spins at 75 Hz.
pub const MIRROR_TURN: Duration = Duration::from_nanos(1_000_000_000 / 75);

/// Angular range and resolution (command `3B`): 180° or 100°, in steps of 1°, 0.5° or
/// 0.25° (0.25° only over 100°).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Variant {
    /// Scanning angle (degrees): 100 or 180.
    pub angle_deg: u16,
    /// Angular resolution (hundredths of a degree): 25, 50 or 100.
    pub resolution_cdeg: u16,
}

impl Variant {
    /// The paper's LMS 221 setting: 180° at 0.5°.
    pub const DEFAULT: Variant = Variant {
        angle_deg: 180,
        resolution_cdeg: 50,
    };

    /// Whether an LMS 2xx offers this combination.
    pub fn is_supported(self) -> bool {
        matches!(
            (self.angle_deg, self.resolution_cdeg),
            (180, 50) | (180, 100) | (100, 25) | (100, 50) | (100, 100)
        )
    }

    /// Number of values in one scan: angle / resolution + 1.
    pub fn values(self) -> usize {
        usize::from(self.angle_deg) * 100 / usize::from(self.resolution_cdeg.max(1)) + 1
    }

    /// Mirror turns one scan takes: finer resolutions interlace turns offset by the
    /// resolution (1° in one turn, 0.5° in two, 0.25° in four).
    pub fn turns(self) -> u32 {
        u32::from((100 / self.resolution_cdeg.max(1)).max(1))
    }

    /// Time from a scan's first beam to its last: the turns before the last one, and the
    /// scanned angle of the last.
    pub fn sweep_duration(self) -> Duration {
        MIRROR_TURN * (self.turns() - 1) + MIRROR_TURN * u32::from(self.angle_deg) / 360
    }

    /// Bytes of this variant's `B0` telegram on the wire: frame, CMD, count word, two
    /// bytes per value, STATUS.
    pub fn telegram_bytes(self) -> usize {
        FRAME_OVERHEAD + 1 + 2 + 2 * self.values() + 1
    }

    /// The request telegram `3B angle(u16 LE) resolution(u16 LE)`.
    pub fn request(self) -> Telegram {
        let mut data = self.angle_deg.to_le_bytes().to_vec();
        data.extend_from_slice(&self.resolution_cdeg.to_le_bytes());
        Telegram::request(CMD_VARIANT, &data)
    }

    /// The variant of a `3B` request's data or of a `BB` reply's payload after its
    /// success byte.
    pub fn from_bytes(bytes: &[u8]) -> Option<Self> {
        let [a0, a1, r0, r1, ..] = *bytes else {
            return None;
        };
        Some(Variant {
            angle_deg: u16::from_le_bytes([a0, a1]),
            resolution_cdeg: u16::from_le_bytes([r0, r1]),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn requests_encode_as_the_design_vectors() {
        assert_eq!(
            Mode::Continuous.request().encode(),
            [0x02, 0x00, 0x02, 0x00, 0x20, 0x24, 0x34, 0x08]
        );
        assert_eq!(
            Mode::Stop.request().encode(),
            [0x02, 0x00, 0x02, 0x00, 0x20, 0x25, 0x35, 0x08]
        );
        assert_eq!(
            Mode::Baud(BaudRate::B38400).request().encode(),
            [0x02, 0x00, 0x02, 0x00, 0x20, 0x40, 0x50, 0x08]
        );
    }

    #[test]
    fn modes_and_variants_round_trip() {
        for code in 0..=255u8 {
            if let Some(mode) = Mode::from_code(code) {
                assert_eq!(mode.code(), code);
            }
        }
        let v = Variant {
            angle_deg: 100,
            resolution_cdeg: 25,
        };
        assert_eq!(Variant::from_bytes(&v.request().data), Some(v));
        assert_eq!(v.values(), 401);
        assert_eq!(Variant::DEFAULT.values(), 361);
        assert!(!Variant {
            angle_deg: 180,
            resolution_cdeg: 25
        }
        .is_supported());
        let reply = Telegram::reply(REPLY_MODE, &[0x00], 0x10);
        assert_eq!((reply.payload(), reply.status()), (&[0x00][..], Some(0x10)));
    }

    #[test]
    fn line_and_sweep_times() {
        // 180° at 0.5°: 361 values, a 732-byte telegram, 190.6 ms at 38400 baud.
        assert_eq!(Variant::DEFAULT.telegram_bytes(), 732);
        let t = BaudRate::B38400.transmission_time(Variant::DEFAULT.telegram_bytes());
        assert_eq!(t.as_micros(), 190_625);
        assert_eq!(BaudRate::B9600.byte_time().as_micros(), 1041);
        // Two interlaced turns: 13.3 ms + half a turn for 180°: 20 ms.
        assert_eq!(Variant::DEFAULT.sweep_duration().as_millis(), 19);
        let fine = Variant {
            angle_deg: 100,
            resolution_cdeg: 25,
        };
        assert_eq!(fine.turns(), 4);
        assert_eq!(fine.telegram_bytes(), 2 * 401 + 10);
    }
}
