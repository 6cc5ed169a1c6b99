//! The Python module `ekf_loc` (distribution `ekf-loc`): the EKF localization stack of
//! this workspace with numpy arrays in and out.
//!
//! - [`filter::Filter`]: the extended Kalman filter one call at a time (predict from wheel
//!   speeds or odometry deltas, compass and laser-line updates) and, through
//!   [`batch`], a whole sequence in one native call;
//! - [`lines::extract_lines`], [`map::LineMap`], [`map::MapBuilder`],
//!   [`matching::match_lines`]: line features, maps and data association;
//! - [`localizer::Localizer`]: the `lrf_lines::Localizer` facade;
//! - [`replay::replay`]: `ekf replay` on a ROS 2 bag, with trajectories as arrays;
//! - [`simulate::simulate`]: `ekf simulate`'s scenarios, with the truth as arrays.
//!
//! Conventions (ROS REP-103): SI units and radians; world x east, y north; robot x
//! forward, y left; headings counter-clockwise from the world x axis, wrapped to
//! (−π, π]; a pose is `(x, y, θ)` and its covariance 3×3 in that order. Errors become
//! `ValueError` or `OSError` ([`errors`]); nothing here panics on any input.

pub mod arrays;
pub mod batch;
pub mod core;
pub mod errors;
pub mod filter;
pub mod lines;
pub mod localizer;
pub mod map;
pub mod matching;
pub mod params;
pub mod replay;
pub mod simulate;
pub mod timed;

use pyo3::prelude::*;

/// The native part of `ekf_loc`; import `ekf_loc`, which re-exports everything here.
#[pymodule]
fn _ekf_loc(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<filter::Filter>()?;
    m.add_class::<filter::UpdateOutcome>()?;
    m.add_class::<filter::LineUpdates>()?;
    m.add_class::<batch::BatchResult>()?;
    m.add_class::<lines::Lines>()?;
    m.add_class::<map::LineMap>()?;
    m.add_class::<map::MapBuilder>()?;
    m.add_class::<matching::Matches>()?;
    m.add_class::<localizer::Localizer>()?;
    m.add_class::<localizer::CompassUpdate>()?;
    m.add_class::<timed::TimedLocalizer>()?;
    m.add_class::<replay::ReplayResult>()?;
    m.add_class::<simulate::SimulationResult>()?;
    m.add_function(wrap_pyfunction!(lines::extract_lines, m)?)?;
    m.add_function(wrap_pyfunction!(matching::match_lines, m)?)?;
    m.add_function(wrap_pyfunction!(replay::replay, m)?)?;
    m.add_function(wrap_pyfunction!(simulate::simulate, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    // Benchmarks refuse to time an unoptimised build.
    m.setattr("_debug_build", cfg!(debug_assertions))?;
    Ok(())
}
