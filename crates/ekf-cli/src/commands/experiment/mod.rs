//! `ekf experiment fig9|fig11|fig12 --out-dir DIR`: the paper's experiments (§IV) in
//! simulation, each writing an SVG figure and a JSON table of its numbers into `DIR`.
//!
//! - [`fig9`]: one run estimated four ways (Fig. 9/10), repeated over seeds for the
//!   ordering of the estimators and the filter's consistency (NEES);
//! - [`fig11`]: a rounded rectangle and a rounded triangle followed with the true pose,
//!   the EKF, or odometry alone in the loop;
//! - [`fig12`]: driving round close to the walls of the map extracted from the first scan.

pub mod fig11;
pub mod fig12;
pub mod fig9;

use super::simulate::SimulateError;
use crate::commands::compare::CompareError;
use crate::config::ConfigError;
use crate::plot::PlotError;
use crate::replay::ReplayError;
use crate::sim::{ScenarioError, SimError};
use serde::Serialize;
use std::path::{Path, PathBuf};

/// Settings shared by the experiments.
#[derive(Debug, Clone)]
pub struct ExperimentOptions {
    /// Where the SVG, the JSON table and any log go (created if missing).
    pub out_dir: PathBuf,
    /// The first seed.
    pub seed: u64,
    /// How many seeds (consecutive from `seed`); experiments that show one run use the
    /// first.
    pub seeds: u32,
    /// Simulated time per run (s); `None`: the scenario's.
    pub duration_s: Option<f64>,
}

/// Why an experiment failed.
#[derive(Debug, thiserror::Error)]
pub enum ExperimentError {
    /// The output folder or a file in it could not be written.
    #[error("{path}: {source}")]
    Io {
        /// The file or folder.
        path: String,
        /// What the OS said.
        source: std::io::Error,
    },
    /// The scenario could not be set up.
    #[error(transparent)]
    Scenario(#[from] ScenarioError),
    /// A simulation failed.
    #[error(transparent)]
    Simulate(#[from] SimulateError),
    /// A simulation failed.
    #[error(transparent)]
    Sim(#[from] SimError),
    /// A log could not be written.
    #[error(transparent)]
    Write(#[from] crate::mcap_io::WriteError),
    /// The comparison of the estimators failed.
    #[error(transparent)]
    Compare(#[from] CompareError),
    /// A replay failed.
    #[error(transparent)]
    Replay(#[from] ReplayError),
    /// The built-in preset did not load.
    #[error(transparent)]
    Config(#[from] ConfigError),
    /// A figure could not be drawn.
    #[error("{path}: {source}")]
    Plot {
        /// The SVG file.
        path: String,
        /// What went wrong.
        source: PlotError,
    },
    /// The experiment's set-up is not possible (e.g. too few walls seen).
    #[error("{0}")]
    Setup(String),
    /// An option is out of range.
    #[error("{0}")]
    Option(String),
}

/// Creates the output folder.
pub(crate) fn prepare_dir(dir: &Path) -> Result<(), ExperimentError> {
    super::create_output_dir(dir).map_err(|source| ExperimentError::Io {
        path: dir.display().to_string(),
        source,
    })
}

/// Writes `value` as pretty JSON to `path`.
pub(crate) fn write_json<T: Serialize>(path: &Path, value: &T) -> Result<(), ExperimentError> {
    let io = |source| ExperimentError::Io {
        path: path.display().to_string(),
        source,
    };
    let text = serde_json::to_string_pretty(value).map_err(|e| io(e.into()))?;
    std::fs::write(path, text + "\n").map_err(io)
}

/// Draws an SVG with `draw` into `path`.
pub(crate) fn write_svg(
    path: &Path,
    draw: impl FnOnce(std::io::BufWriter<std::fs::File>) -> Result<(), PlotError>,
) -> Result<(), ExperimentError> {
    let name = path.display().to_string();
    let file = std::fs::File::create(path).map_err(|source| ExperimentError::Io {
        path: name.clone(),
        source,
    })?;
    draw(std::io::BufWriter::new(file))
        .map_err(|source| ExperimentError::Plot { path: name, source })
}

/// Root mean square of `values` (0 for none).
pub(crate) fn rms(values: impl IntoIterator<Item = f64>) -> f64 {
    let (sum, n) = values
        .into_iter()
        .fold((0.0, 0usize), |(s, n), v| (s + v * v, n + 1));
    if n == 0 {
        0.0
    } else {
        (sum / n as f64).sqrt()
    }
}
