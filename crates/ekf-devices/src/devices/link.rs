//! A serial line as the drivers see it: bytes both ways with a short read timeout, and a
//! settable baud rate. [`SerialLink`] is the real port (`serialport`).

use super::DeviceError;
use std::io::{self, Read, Write};
use std::time::Duration;

/// How long one read waits before returning nothing; drivers loop on it with their own
/// deadlines, so it only bounds how late a deadline or a stop request is noticed.
pub const READ_SLICE: Duration = Duration::from_millis(20);

/// A byte link to a device.
pub trait Link: Send {
    /// Reads what is there, waiting at most [`READ_SLICE`]; `Ok(0)` when nothing came.
    fn read_some(&mut self, buf: &mut [u8]) -> io::Result<usize>;
    /// Writes all of `bytes`.
    fn write_all_bytes(&mut self, bytes: &[u8]) -> io::Result<()>;
    /// Changes the host side's baud rate.
    fn set_baud_rate(&mut self, bps: u32) -> io::Result<()>;
    /// Discards bytes received but not read.
    fn clear_input(&mut self) -> io::Result<()>;
    /// The port's path, for messages.
    fn name(&self) -> &str;

    /// `device`'s I/O error on this port while `during`.
    fn io_error(
        &self,
        device: &'static str,
        during: &'static str,
        source: io::Error,
    ) -> DeviceError {
        DeviceError::Io {
            device,
            port: self.name().into(),
            during,
            source,
        }
    }

    /// `device` on this port sent nothing usable for `waited`; `expected` says what.
    fn silent(&self, device: &'static str, waited: Duration, expected: String) -> DeviceError {
        DeviceError::Silent {
            device,
            port: self.name().into(),
            waited,
            expected,
        }
    }

    /// `device` on this port refused a request, or the request could not be made.
    fn refused(&self, device: &'static str, message: String) -> DeviceError {
        DeviceError::Refused {
            device,
            port: self.name().into(),
            message,
        }
    }
}

/// A serial port opened by path (8N1, no flow control).
pub struct SerialLink {
    port: Box<dyn serialport::SerialPort>,
    name: String,
}

impl SerialLink {
    /// Opens `path` at `bps` for `device` (named in errors). When that fails on a path
    /// that is a regular file or a folder, the error says it is not a serial port rather
    /// than what the OS said of the ioctl ("Not a typewriter").
    pub fn open(device: &'static str, path: &str, bps: u32) -> Result<Self, DeviceError> {
        let port = serialport::new(path, bps)
            .timeout(READ_SLICE)
            .open()
            .map_err(|e| {
                let kind = std::fs::metadata(path).ok().map(|m| m.file_type());
                let message = match kind {
                    Some(t) if t.is_file() => "not a serial port but a regular file".into(),
                    Some(t) if t.is_dir() => "not a serial port but a folder".into(),
                    _ => e.to_string(),
                };
                DeviceError::Open {
                    device,
                    port: path.into(),
                    message,
                }
            })?;
        Ok(Self {
            port,
            name: path.into(),
        })
    }
}

impl Link for SerialLink {
    fn read_some(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        match self.port.read(buf) {
            // A tty read of 0 bytes after poll said "readable" is a hang-up.
            Ok(0) => Err(io::Error::new(
                io::ErrorKind::UnexpectedEof,
                "the line hung up",
            )),
            Ok(n) => Ok(n),
            Err(e) if e.kind() == io::ErrorKind::TimedOut => Ok(0),
            Err(e) => Err(e),
        }
    }

    fn write_all_bytes(&mut self, bytes: &[u8]) -> io::Result<()> {
        self.port.write_all(bytes)?;
        self.port.flush()
    }

    fn set_baud_rate(&mut self, bps: u32) -> io::Result<()> {
        self.port.set_baud_rate(bps).map_err(io::Error::from)
    }

    fn clear_input(&mut self) -> io::Result<()> {
        self.port
            .clear(serialport::ClearBuffer::Input)
            .map_err(io::Error::from)
    }

    fn name(&self) -> &str {
        &self.name
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn open_error(path: &std::path::Path) -> String {
        match SerialLink::open("laser", path.to_str().unwrap(), 9600) {
            Ok(_) => panic!("{} opened as a serial port", path.display()),
            Err(e) => e.to_string(),
        }
    }

    #[test]
    fn a_file_or_folder_given_as_port_is_not_a_serial_port() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("scan.mcap");
        std::fs::write(&file, b"not a tty").unwrap();
        assert_eq!(
            open_error(&file),
            format!(
                "laser on {}: cannot open: not a serial port but a regular file",
                file.display()
            )
        );
        assert!(open_error(dir.path()).ends_with("not a serial port but a folder"));
        let missing = dir.path().join("ttyUSB9");
        let e = open_error(&missing);
        assert!(
            e.starts_with(&format!("laser on {}: cannot open: ", missing.display()))
                && !e.contains("not a serial port"),
            "{e}"
        );
    }
}
