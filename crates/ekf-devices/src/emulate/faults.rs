//! Faults an emulated device can be told to commit, and the state that applies them to
//! its next outputs.

use std::time::{Duration, Instant};

/// A fault to inject.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Fault {
    /// This many noise bytes before the next output.
    Garbage(usize),
    /// The next output is cut after half its bytes.
    Truncate,
    /// The next output has a wrong checksum (CRC or NMEA checksum).
    BadChecksum,
    /// The next reply is a MODBUS exception with this code (base only).
    Exception(u8),
    /// Neither answer nor send anything for this long.
    Silence(Duration),
    /// Unplug: the pseudo-terminal disappears and comes back after this long.
    Disconnect(Duration),
}

/// Armed byte-level faults.
#[derive(Debug, Default)]
pub(crate) struct FaultState {
    garbage: usize,
    truncate: bool,
    bad_checksum: bool,
    silent_until: Option<Instant>,
    noise: u32,
}

impl FaultState {
    /// Arms a byte-level fault or a silence; returns the fault back if it is not one.
    pub(crate) fn arm(&mut self, fault: Fault) -> Option<Fault> {
        match fault {
            Fault::Garbage(n) => self.garbage += n,
            Fault::Truncate => self.truncate = true,
            Fault::BadChecksum => self.bad_checksum = true,
            Fault::Silence(d) => self.silent_until = Some(Instant::now() + d),
            other => return Some(other),
        }
        None
    }

    /// Whether the device is keeping silent.
    pub(crate) fn silent(&mut self) -> bool {
        match self.silent_until {
            Some(t) if Instant::now() < t => true,
            _ => {
                self.silent_until = None;
                false
            }
        }
    }

    /// Applies the armed faults to an output; `checksum_at` is the index of a checksum
    /// byte in it.
    pub(crate) fn apply(&mut self, mut out: Vec<u8>, checksum_at: usize) -> Vec<u8> {
        if out.is_empty() {
            return out;
        }
        if std::mem::take(&mut self.bad_checksum) {
            let i = checksum_at.min(out.len() - 1);
            // Flip to another hex digit for NMEA, any other byte for binary checksums.
            out[i] = if out[i].is_ascii_hexdigit() {
                if out[i] == b'0' {
                    b'1'
                } else {
                    b'0'
                }
            } else {
                out[i] ^ 0x5a
            };
        }
        if std::mem::take(&mut self.truncate) {
            out.truncate(out.len() / 2);
        }
        let n = std::mem::take(&mut self.garbage);
        let mut noisy: Vec<u8> = (0..n).map(|_| self.noise_byte()).collect();
        noisy.extend(out);
        noisy
    }

    /// Xorshift noise: deterministic, no dependency.
    fn noise_byte(&mut self) -> u8 {
        let mut x = self.noise.wrapping_add(0x9e37_79b9) | 1;
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        self.noise = x;
        (x >> 24) as u8
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn faults_apply_once() {
        let mut f = FaultState::default();
        assert_eq!(f.arm(Fault::Exception(4)), Some(Fault::Exception(4)));
        f.arm(Fault::Garbage(3));
        f.arm(Fault::BadChecksum);
        let out = f.apply(vec![1, 2, 3, 4], 3);
        assert_eq!(out.len(), 7);
        assert_eq!(&out[3..6], &[1, 2, 3]);
        assert_ne!(out[6], 4);
        f.arm(Fault::Truncate);
        assert_eq!(f.apply(vec![1, 2, 3, 4], 3), vec![1, 2]);
        assert_eq!(f.apply(vec![1, 2, 3, 4], 3), vec![1, 2, 3, 4]);
        assert!(!f.silent());
        f.arm(Fault::Silence(Duration::from_secs(60)));
        assert!(f.silent());
    }
}
