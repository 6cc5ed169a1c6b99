//! One thread per emulated device: owns its pseudo-terminal, answers the host, sends
//! output for new samples, and commits the faults it is told to.

use super::devices::Emulated;
use super::faults::{Fault, FaultState};
use super::pty::Pty;
use super::RobotSample;
use std::io::{self, Read, Write};
use std::path::PathBuf;
use std::sync::mpsc::{self, Receiver, RecvTimeoutError, Sender, TryRecvError};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Instant;

/// What a device thread is told.
pub(crate) enum Command {
    /// The robot's state now.
    Sample(Arc<RobotSample>),
    /// A fault to commit, and where to say it was taken on.
    Fault(Fault, Sender<()>),
    /// End.
    Stop,
}

/// Starts `device` on a new pseudo-terminal reached through `link`.
pub(crate) fn spawn<D: Emulated>(
    device: D,
    link: PathBuf,
) -> io::Result<(Sender<Command>, JoinHandle<()>)> {
    let pty = Pty::open(&link)?;
    let (tx, rx) = mpsc::channel();
    let thread = std::thread::spawn(move || {
        Runner {
            device,
            link,
            rx,
            sample: None,
            faults: FaultState::default(),
        }
        .run(pty);
    });
    Ok((tx, thread))
}

struct Runner<D> {
    device: D,
    link: PathBuf,
    rx: Receiver<Command>,
    sample: Option<Arc<RobotSample>>,
    faults: FaultState,
}

/// Why the inner loop ended.
enum Next {
    Replug(std::time::Duration),
    Stop,
}

impl<D: Emulated> Runner<D> {
    fn run(mut self, mut pty: Pty) {
        loop {
            match self.serve(&mut pty) {
                Next::Stop => break,
                Next::Replug(after) => {
                    drop(pty);
                    let _ = std::fs::remove_file(&self.link);
                    if !self.wait(after) {
                        break;
                    }
                    match Pty::open(&self.link) {
                        Ok(p) => pty = p,
                        Err(_) => break,
                    }
                    self.device.power_up();
                }
            }
        }
        let _ = std::fs::remove_file(&self.link);
    }

    /// Serves the host until a replug or stop.
    fn serve(&mut self, pty: &mut Pty) -> Next {
        let mut buf = [0u8; 1024];
        loop {
            loop {
                match self.rx.try_recv() {
                    Ok(Command::Sample(s)) => {
                        let out = self.device.output(&s);
                        self.sample = Some(s);
                        if let Some(out) = out {
                            self.send(pty, out);
                        }
                    }
                    Ok(Command::Fault(fault, taken)) => {
                        let _ = taken.send(());
                        match fault {
                            Fault::Disconnect(after) => return Next::Replug(after),
                            Fault::Exception(code) => {
                                self.device.fail_next(code);
                            }
                            other => {
                                self.faults.arm(other);
                            }
                        }
                    }
                    Ok(Command::Stop) | Err(TryRecvError::Disconnected) => return Next::Stop,
                    Err(TryRecvError::Empty) => break,
                }
            }
            // Host bytes (the read waits a few milliseconds when there are none).
            // A timeout (no host bytes) reads as nothing.
            let n: usize = pty.device.read(&mut buf).unwrap_or_default();
            if n > 0 && !self.faults.silent() {
                for reply in self.device.answer(&buf[..n], self.sample.as_deref()) {
                    self.send(pty, reply);
                }
            }
        }
    }

    fn send(&mut self, pty: &mut Pty, out: Vec<u8>) {
        if self.faults.silent() {
            return;
        }
        let at = self.device.checksum_at(&out);
        let bytes = self.faults.apply(out, at);
        // Nobody listening (the host not connected) is not the device's problem.
        let _ = pty
            .device
            .write_all(&bytes)
            .and_then(|()| pty.device.flush());
    }

    /// Waits `duration` while unplugged, keeping the latest sample; `false` on stop.
    fn wait(&mut self, duration: std::time::Duration) -> bool {
        let until = Instant::now() + duration;
        loop {
            let left = until.saturating_duration_since(Instant::now());
            if left.is_zero() {
                return true;
            }
            match self.rx.recv_timeout(left) {
                Ok(Command::Sample(s)) => self.sample = Some(s),
                Ok(Command::Fault(_, taken)) => {
                    let _ = taken.send(());
                }
                Ok(Command::Stop) | Err(RecvTimeoutError::Disconnected) => return false,
                Err(RecvTimeoutError::Timeout) => return true,
            }
        }
    }
}
