//! A pseudo-terminal for one emulated device, reached through a symlink that is
//! replaced atomically when the device comes back on a new terminal.

use serialport::{SerialPort, TTYPort};
use std::io;
use std::path::Path;
use std::time::Duration;

/// How long a read of the device side waits for host bytes; also how late a new sample's
/// output (a laser telegram) may leave.
const POLL: Duration = Duration::from_millis(2);

/// The device side of a pseudo-terminal; the host side is kept open so the device side
/// does not see hang-ups while no host is connected.
pub(crate) struct Pty {
    pub(crate) device: TTYPort,
    _host: TTYPort,
}

impl Pty {
    /// Opens a new pseudo-terminal and points `link` at its host side.
    pub(crate) fn open(link: &Path) -> io::Result<Self> {
        let (mut device, host) = TTYPort::pair().map_err(io::Error::from)?;
        device.set_timeout(POLL).map_err(io::Error::from)?;
        let target = host
            .name()
            .ok_or_else(|| io::Error::other("the pseudo-terminal has no name"))?;
        let tmp = link.with_extension("new");
        let _ = std::fs::remove_file(&tmp);
        std::os::unix::fs::symlink(target, &tmp)?;
        std::fs::rename(&tmp, link)?;
        Ok(Self {
            device,
            _host: host,
        })
    }
}
