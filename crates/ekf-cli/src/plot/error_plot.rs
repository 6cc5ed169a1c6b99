//! Errors over time: several named series (e.g. the position error of each estimate, or
//! its x and y error as the paper's Fig. 10) against time.

use super::axes::{
    build_chart, colour, draw_markers, draw_series, layered_width, padded_range, render,
    with_legend, Glyph, LegendEntry,
};
use super::trajectory_plot::marker_entry;
use super::{Markers, PlotError, PlotOptions};
use plotters::coord::Shift;
use plotters::prelude::{DrawingArea, SVGBackend};
use plotters::style::RGBColor;
use std::io::Write;
use std::ops::Range;

/// A named series of `(stamp in ns, value)` points, e.g. from
/// [`crate::eval::Ape::errors`]: `ape.errors.iter().map(|e| (e.t_ns, e.dx))`.
#[derive(Debug, Clone, Copy)]
pub struct TimeSeries<'a> {
    /// Legend name.
    pub name: &'a str,
    /// The points, `(t_ns, value)`.
    pub points: &'a [(u64, f64)],
}

/// Plots each series as a line of value against time and writes the SVG to `writer`.
///
/// The time axis is in seconds since the earliest stamp of all series (computed from
/// the integer stamps, so large epochs lose no precision); `y_desc` labels the value
/// axis (e.g. `"position error [m]"`). Each series is one `<polyline>` with a legend
/// entry, coloured in order. Fails with [`PlotError::NoData`] if no series has a
/// finite value.
pub fn plot_errors_over_time<W: Write>(
    writer: W,
    series: &[TimeSeries<'_>],
    y_desc: &str,
    options: &PlotOptions,
) -> Result<(), PlotError> {
    let ranges = time_ranges(series)?;
    render(writer, options, |area| {
        draw_errors(area, &ranges, series, &[], y_desc)
    })
}

/// The earliest stamp and the time (s) and value ranges of `series`.
pub(super) struct TimeRanges {
    t0: u64,
    x: Range<f64>,
    y: Range<f64>,
}

/// The ranges of `series`; [`PlotError::NoData`] if no series has a finite value.
pub(super) fn time_ranges(series: &[TimeSeries<'_>]) -> Result<TimeRanges, PlotError> {
    let t0 = series
        .iter()
        .flat_map(|s| s.points.iter().map(|&(t, _)| t))
        .min()
        .ok_or(PlotError::NoData)?;
    let seconds = |t: u64| (t - t0) as f64 * 1e-9;
    let values = || series.iter().flat_map(|s| s.points.iter().map(|&(_, v)| v));
    let y = padded_range(values()).ok_or(PlotError::NoData)?;
    let times = series
        .iter()
        .flat_map(|s| s.points.iter().map(|&(t, _)| seconds(t)));
    let x = padded_range(times).ok_or(PlotError::NoData)?;
    Ok(TimeRanges { t0, x, y })
}

/// Draws the error chart on `area` (ranges from [`time_ranges`]) with the legend above
/// it: the series in order, each narrower than the one before so that none hides
/// another, then the markers.
pub(super) fn draw_errors(
    area: &DrawingArea<SVGBackend<'_>, Shift>,
    ranges: &TimeRanges,
    series: &[TimeSeries<'_>],
    markers: &[Markers<'_, (u64, f64)>],
    y_desc: &str,
) -> Result<(), PlotError> {
    let t0 = ranges.t0;
    let seconds = |t: u64| t.saturating_sub(t0) as f64 * 1e-9;
    let n = series.len();
    let mut legend: Vec<LegendEntry> = series
        .iter()
        .enumerate()
        .map(|(i, s)| LegendEntry {
            name: s.name.into(),
            glyph: Glyph::Line(colour(i), layered_width(i, n)),
        })
        .collect();
    legend.extend(markers.iter().map(marker_entry));
    let area = with_legend(area, &legend)?;
    let (x, y) = (ranges.x.clone(), ranges.y.clone());
    let mut chart = build_chart(&area, "time [s]", y_desc, |_| (x, y))?;
    for (i, s) in series.iter().enumerate() {
        let points = s.points.iter().map(|&(t, v)| (seconds(t), v));
        draw_series(&mut chart, points, colour(i), layered_width(i, n))?;
    }
    for m in markers {
        let (r, g, b) = m.colour;
        let points = m.points.iter().map(|&(t, v)| (seconds(t), v));
        draw_markers(&mut chart, points, RGBColor(r, g, b), m.shape)?;
    }
    Ok(())
}
