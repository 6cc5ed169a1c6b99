//! SICK LMS 2xx over RS-232/422: telegrams and their CRC, a resynchronising stream
//! parser, measured values (`B0`), the host driver, and the scanner side for emulation.

pub mod crc;
pub mod device;
pub mod driver;
pub mod measured;
pub mod parser;
pub mod telegram;

pub use driver::{Scan, SickConfig, SickCounters, SickLaser};
pub use measured::{MeasuredValues, RangeUnit};
pub use parser::{Discard, DiscardKind, Event, ParserStats, TelegramParser};
pub use telegram::{BaudRate, Mode, Telegram, Variant};
