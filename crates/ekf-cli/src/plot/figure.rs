//! Several charts in one SVG image, on a grid: e.g. the paper's Fig. 9 (trajectories)
//! next to its Fig. 10 (x and y errors over time).

use super::axes::{render, LABEL_SIZE, MIN_SIZE};
use super::error_plot::{draw_errors, time_ranges, TimeRanges};
use super::trajectory_plot::{draw_trajectories, trajectory_ranges};
use super::{Markers, PlotError, PlotOptions, TimeSeries, TrajectorySeries, Wall};
use std::io::Write;
use std::ops::Range;

/// One chart of a figure, with the same content as the single-chart functions.
#[derive(Debug, Clone, Copy)]
pub enum Panel<'a> {
    /// As [`super::plot_trajectories`]: the reference (black) and the estimates in the x–y
    /// plane, equal scales.
    Trajectories {
        /// Title above the chart (empty: none).
        title: &'a str,
        /// The reference, drawn in black.
        reference: Option<TrajectorySeries<'a>>,
        /// The estimates, coloured in order.
        estimates: &'a [TrajectorySeries<'a>],
        /// Walls drawn in grey under the trajectories (legend entry `walls`), e.g. a
        /// line map; may be empty.
        walls: &'a [Wall],
        /// Event markers over the trajectories; may be empty.
        markers: &'a [Markers<'a, (f64, f64)>],
    },
    /// As [`super::plot_errors_over_time`]: values against time (s since the panel's
    /// earliest stamp).
    ErrorsOverTime {
        /// Title above the chart (empty: none).
        title: &'a str,
        /// The series, coloured in order.
        series: &'a [TimeSeries<'a>],
        /// Description of the value axis.
        y_desc: &'a str,
        /// Event markers over the series; may be empty.
        markers: &'a [Markers<'a, (u64, f64)>],
    },
}

/// A panel with its data ranges, computed before anything is drawn.
enum Prepared<'p, 'a> {
    Trajectories {
        ranges: (Range<f64>, Range<f64>),
        reference: Option<&'p TrajectorySeries<'a>>,
        estimates: &'a [TrajectorySeries<'a>],
        walls: &'a [Wall],
        markers: &'a [Markers<'a, (f64, f64)>],
    },
    Errors {
        ranges: TimeRanges,
        series: &'a [TimeSeries<'a>],
        y_desc: &'a str,
        markers: &'a [Markers<'a, (u64, f64)>],
    },
}

/// Draws `panels` row by row on a grid of `columns` columns (as many rows as needed) in
/// one SVG image of `options`' size (`options.title` above the grid) and writes it to
/// `writer`.
///
/// Each panel is drawn as its single-chart function draws it: one `<polyline>` and one
/// legend entry per series. Fails with [`PlotError::NoData`] if there is no panel or a
/// panel has no finite point, and with [`PlotError::TooSmall`] if a grid cell is smaller
/// than a single chart may be.
pub fn plot_figure<W: Write>(
    writer: W,
    panels: &[Panel<'_>],
    columns: usize,
    options: &PlotOptions,
) -> Result<(), PlotError> {
    if panels.is_empty() {
        return Err(PlotError::NoData);
    }
    let columns = columns.clamp(1, panels.len());
    let rows = panels.len().div_ceil(columns);
    let prepared = panels
        .iter()
        .map(|p| -> Result<Prepared<'_, '_>, PlotError> {
            match p {
                Panel::Trajectories {
                    reference,
                    estimates,
                    walls,
                    markers,
                    ..
                } => Ok(Prepared::Trajectories {
                    ranges: trajectory_ranges(reference.as_ref(), estimates, walls)?,
                    reference: reference.as_ref(),
                    estimates,
                    walls,
                    markers,
                }),
                Panel::ErrorsOverTime {
                    series,
                    y_desc,
                    markers,
                    ..
                } => Ok(Prepared::Errors {
                    ranges: time_ranges(series)?,
                    series,
                    y_desc,
                    markers,
                }),
            }
        })
        .collect::<Result<Vec<_>, _>>()?;
    let (columns_u32, rows_u32) = (
        u32::try_from(columns).unwrap_or(u32::MAX),
        u32::try_from(rows).unwrap_or(u32::MAX),
    );
    if options.width / columns_u32 < MIN_SIZE || options.height / rows_u32 < MIN_SIZE {
        return Err(PlotError::TooSmall {
            width: options.width,
            height: options.height,
            min: MIN_SIZE.saturating_mul(columns_u32.max(rows_u32)),
        });
    }
    render(writer, options, |area| {
        let cells = area.split_evenly((rows, columns));
        for ((panel, prepared), cell) in panels.iter().zip(prepared).zip(&cells) {
            let title = match panel {
                Panel::Trajectories { title, .. } | Panel::ErrorsOverTime { title, .. } => *title,
            };
            let titled;
            let area = if title.is_empty() {
                cell
            } else {
                titled = cell.titled(title, ("sans-serif", LABEL_SIZE + 2))?;
                &titled
            };
            match prepared {
                Prepared::Trajectories {
                    ranges,
                    reference,
                    estimates,
                    walls,
                    markers,
                } => draw_trajectories(area, ranges, reference, estimates, walls, markers)?,
                Prepared::Errors {
                    ranges,
                    series,
                    y_desc,
                    markers,
                } => draw_errors(area, &ranges, series, markers, y_desc)?,
            }
        }
        Ok(())
    })
}
