//! Where the replay's poses go, as they are made: the TUM file (streamed), the online
//! accuracy, and — only when asked — trajectories kept in memory for plots.

use super::accuracy::{AccuracyTotals, OnlineAccuracy};
use super::ReplayError;
use crate::trajectory::{StampedPose, Trajectory};
use crate::tum::{write_tum_header, write_tum_row};
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// Receives estimated and reference poses in log-time order.
pub struct PoseSink {
    tum: Option<(PathBuf, BufWriter<File>)>,
    /// The last estimate, held back until a later stamp arrives: of several poses with
    /// one stamp (a motion step and a scan update), only the last is kept.
    held: Option<StampedPose>,
    kept: Option<(Trajectory, Trajectory)>,
    accuracy: OnlineAccuracy,
    written: u64,
}

/// What the sink produced.
pub struct SinkResult {
    /// Estimated poses written (TUM rows).
    pub written: u64,
    /// The estimate and reference, when kept.
    pub kept: Option<(Trajectory, Trajectory)>,
    /// Accuracy against the reference, when it had poses to pair.
    pub accuracy: Option<AccuracyTotals>,
}

fn tum_error(path: &Path) -> impl Fn(std::io::Error) -> ReplayError + '_ {
    move |source| ReplayError::Tum {
        path: path.display().to_string(),
        source,
    }
}

impl PoseSink {
    /// A sink writing TUM to `tum` (created now) and keeping trajectories if `keep`.
    pub fn new(tum: Option<&Path>, keep: bool) -> Result<Self, ReplayError> {
        let tum = match tum {
            Some(path) => {
                let mut file = BufWriter::new(File::create(path).map_err(tum_error(path))?);
                write_tum_header(&mut file).map_err(tum_error(path))?;
                Some((path.to_path_buf(), file))
            }
            None => None,
        };
        Ok(Self {
            tum,
            held: None,
            kept: keep.then(Default::default),
            accuracy: OnlineAccuracy::default(),
            written: 0,
        })
    }

    /// An estimated pose.
    pub fn estimate(&mut self, sample: StampedPose) -> Result<(), ReplayError> {
        self.accuracy.estimate(sample);
        match self.held.replace(sample) {
            Some(previous) if previous.t_ns != sample.t_ns => self.emit(previous),
            _ => Ok(()),
        }
    }

    /// A reference pose.
    pub fn reference(&mut self, sample: StampedPose) {
        self.accuracy.reference(sample);
        if let Some((_, reference)) = &mut self.kept {
            reference.samples.push(sample);
        }
    }

    /// Writes an estimate whose stamp is final.
    fn emit(&mut self, sample: StampedPose) -> Result<(), ReplayError> {
        if let Some((path, file)) = &mut self.tum {
            write_tum_row(file, &sample).map_err(tum_error(path))?;
        }
        if let Some((trajectory, _)) = &mut self.kept {
            trajectory.samples.push(sample);
        }
        self.written += 1;
        Ok(())
    }

    /// Writes the held pose, flushes the TUM file and pairs what is pending.
    pub fn finish(mut self) -> Result<SinkResult, ReplayError> {
        if let Some(last) = self.held.take() {
            self.emit(last)?;
        }
        if let Some((path, mut file)) = self.tum.take() {
            file.flush().map_err(tum_error(&path))?;
        }
        Ok(SinkResult {
            written: self.written,
            kept: self.kept,
            accuracy: self.accuracy.finish(),
        })
    }
}
