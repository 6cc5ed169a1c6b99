//! Where the replay's poses go, as they are made: the TUM file (streamed), the online
//! accuracy, and — only when asked — trajectories kept in memory for plots.

use super::accuracy::{AccuracyTotals, OnlineAccuracy};
use super::ReplayError;
use crate::trajectory::{StampedPose, Trajectory};
use crate::tum::{write_tum_header, write_tum_row};
use nalgebra::Matrix3;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// Receives estimated and reference poses in log-time order.
pub struct PoseSink {
    tum: Option<(PathBuf, BufWriter<File>)>,
    /// The last estimate and its covariance, held back until a later stamp arrives: of
    /// several poses with one stamp (a motion step and a scan update), only the last is
    /// kept.
    held: Option<(StampedPose, Matrix3<f64>)>,
    kept: Option<Kept>,
    accuracy: OnlineAccuracy,
    written: u64,
}

/// The trajectories kept in memory.
#[derive(Debug, Default)]
pub struct Kept {
    /// The estimates, one per TUM row.
    pub estimate: Trajectory,
    /// The covariance of each estimate, `(x, y, θ)`.
    pub covariances: Vec<Matrix3<f64>>,
    /// The reference poses.
    pub reference: Trajectory,
}

/// What the sink produced.
pub struct SinkResult {
    /// Estimated poses written (TUM rows).
    pub written: u64,
    /// The estimates with their covariances and the reference, when kept.
    pub kept: Option<Kept>,
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

    /// An estimated pose with its covariance.
    pub fn estimate(
        &mut self,
        sample: StampedPose,
        covariance: &Matrix3<f64>,
    ) -> Result<(), ReplayError> {
        self.accuracy.estimate(sample);
        match self.held.replace((sample, *covariance)) {
            Some(previous) if previous.0.t_ns != sample.t_ns => self.emit(previous),
            _ => Ok(()),
        }
    }

    /// A `#` comment line in the TUM file (TUM readers, evo's among them, skip them),
    /// after the rows written so far.
    pub fn comment(&mut self, text: &str) -> Result<(), ReplayError> {
        if let Some((path, file)) = &mut self.tum {
            writeln!(file, "# {}", text.replace('\n', " ")).map_err(tum_error(path))?;
        }
        Ok(())
    }

    /// A reference pose.
    pub fn reference(&mut self, sample: StampedPose) {
        self.accuracy.reference(sample);
        if let Some(kept) = &mut self.kept {
            kept.reference.samples.push(sample);
        }
    }

    /// Writes an estimate whose stamp is final.
    fn emit(
        &mut self,
        (sample, covariance): (StampedPose, Matrix3<f64>),
    ) -> Result<(), ReplayError> {
        if let Some((path, file)) = &mut self.tum {
            write_tum_row(file, &sample).map_err(tum_error(path))?;
        }
        if let Some(kept) = &mut self.kept {
            kept.estimate.samples.push(sample);
            kept.covariances.push(covariance);
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

#[cfg(test)]
mod tests {
    use super::*;
    use ekf_core::Pose2;

    #[test]
    fn kept_covariance_belongs_to_the_pose_kept_for_its_stamp() {
        let mut sink = PoseSink::new(None, true).unwrap();
        let pose = |x| Pose2::new(x, 0.0, 0.0);
        let cov = |v| Matrix3::from_diagonal_element(v);
        // A motion step and a scan update at t = 1: only the second is kept.
        sink.estimate(StampedPose::new(1, pose(1.0)), &cov(1.0))
            .unwrap();
        sink.estimate(StampedPose::new(1, pose(2.0)), &cov(2.0))
            .unwrap();
        sink.estimate(StampedPose::new(2, pose(3.0)), &cov(3.0))
            .unwrap();
        let result = sink.finish().unwrap();
        let kept = result.kept.unwrap();
        assert_eq!(result.written, 2);
        let xs: Vec<f64> = kept.estimate.iter().map(|s| s.pose.x).collect();
        assert_eq!(xs, [2.0, 3.0]);
        assert_eq!(kept.covariances, [cov(2.0), cov(3.0)]);
    }
}
