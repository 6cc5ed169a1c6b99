//! One thread per emulated device: owns its pseudo-terminal, answers the host, sends
//! output for new samples, and commits the faults it is told to.

use super::devices::Emulated;
use super::faults::{Fault, FaultState};
use super::pty::Pty;
use super::RobotSample;
use std::collections::VecDeque;
use std::io::{self, Read, Write};
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
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
/// `ready` tells whether a host has brought the device into operation.
pub(crate) fn spawn<D: Emulated>(
    device: D,
    link: PathBuf,
    ready: Arc<AtomicBool>,
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
            ready,
            queue: VecDeque::new(),
            line_free: Instant::now(),
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
    ready: Arc<AtomicBool>,
    /// Bytes waiting to be written, each when its last byte would have arrived on the
    /// device's line.
    queue: VecDeque<(Instant, Vec<u8>)>,
    /// When the line is done with the queued bytes.
    line_free: Instant,
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
                    self.queue.clear();
                    self.ready.store(false, Ordering::Relaxed);
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
                            // Measured now; sent once complete, at the line's pace.
                            let ready = Instant::now() + self.device.output_delay();
                            self.send(out, ready);
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
                    self.send(reply, Instant::now());
                }
                self.ready
                    .store(self.device.host_ready(), Ordering::Relaxed);
            }
            self.write_due(pty);
        }
    }

    /// Queues `out`, ready to go at `ready`, behind what the line still carries: it
    /// arrives whole when its last byte would have ([`Emulated::line_time`]).
    fn send(&mut self, out: Vec<u8>, ready: Instant) {
        if self.faults.silent() {
            return;
        }
        let at = self.device.checksum_at(&out);
        let bytes = self.faults.apply(out, at);
        let due = ready.max(self.line_free) + self.device.line_time(bytes.len());
        self.line_free = due;
        self.queue.push_back((due, bytes));
    }

    /// Writes the queued bytes that are due.
    fn write_due(&mut self, pty: &mut Pty) {
        let now = Instant::now();
        while self.queue.front().is_some_and(|(due, _)| *due <= now) {
            let Some((_, bytes)) = self.queue.pop_front() else {
                break;
            };
            // Nobody listening (the host not connected) is not the device's problem.
            let _ = pty
                .device
                .write_all(&bytes)
                .and_then(|()| pty.device.flush());
        }
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
