//! Trajectories in the x–y plane: the reference and several named estimates, with equal
//! scales on both axes and a legend.

use super::axes::{
    build_chart, colour, draw_markers, draw_series, draw_walls, equal_aspect, layered_width,
    padded_range, render, with_legend, Glyph, LegendEntry, WALL_GREY,
};
use super::{Markers, PlotError, PlotOptions};
use crate::trajectory::Trajectory;
use plotters::coord::Shift;
use plotters::prelude::{DrawingArea, SVGBackend};
use plotters::style::RGBColor;
use plotters::style::BLACK;
use std::io::Write;
use std::ops::Range;

/// A wall to draw: its two end points `[[x, y], [x, y]]` (m).
pub type Wall = [[f64; 2]; 2];

/// A trajectory with the name it gets in the legend.
#[derive(Debug, Clone, Copy)]
pub struct TrajectorySeries<'a> {
    /// Legend name.
    pub name: &'a str,
    /// The poses; only `(x, y)` is drawn.
    pub trajectory: &'a Trajectory,
}

/// Plots `reference` (black) and the `estimates` (coloured in order) as lines in the x–y
/// plane and writes the SVG to `writer`.
///
/// Both axes have the same metres per pixel, so shapes are not distorted; the ranges
/// cover every finite position. Each trajectory is one `<polyline>` and has a legend
/// entry with its name. Fails with [`PlotError::NoData`] if no trajectory has a finite
/// position.
pub fn plot_trajectories<W: Write>(
    writer: W,
    reference: Option<TrajectorySeries<'_>>,
    estimates: &[TrajectorySeries<'_>],
    options: &PlotOptions,
) -> Result<(), PlotError> {
    let ranges = trajectory_ranges(reference.as_ref(), estimates, &[])?;
    render(writer, options, |area| {
        draw_trajectories(area, ranges, reference.as_ref(), estimates, &[], &[])
    })
}

/// The x and y ranges holding every finite position and wall end; [`PlotError::NoData`]
/// if none.
pub(super) fn trajectory_ranges(
    reference: Option<&TrajectorySeries<'_>>,
    estimates: &[TrajectorySeries<'_>],
    walls: &[Wall],
) -> Result<(Range<f64>, Range<f64>), PlotError> {
    let all = || reference.into_iter().chain(estimates);
    let positions = || {
        all()
            .flat_map(|s| s.trajectory.iter().map(|p| (p.pose.x, p.pose.y)))
            .chain(walls.iter().flat_map(|w| w.iter().map(|p| (p[0], p[1]))))
    };
    let x = padded_range(positions().map(|(x, _)| x)).ok_or(PlotError::NoData)?;
    let y = padded_range(positions().map(|(_, y)| y)).ok_or(PlotError::NoData)?;
    Ok((x, y))
}

/// Draws the trajectory chart on `area` (ranges from [`trajectory_ranges`]), with the
/// legend above it: the walls under everything; the estimates in order, each narrower
/// than the one before so that none hides another; the reference on top as a thin black
/// line; the markers over all.
pub(super) fn draw_trajectories(
    area: &DrawingArea<SVGBackend<'_>, Shift>,
    (x, y): (Range<f64>, Range<f64>),
    reference: Option<&TrajectorySeries<'_>>,
    estimates: &[TrajectorySeries<'_>],
    walls: &[Wall],
    markers: &[Markers<'_, (f64, f64)>],
) -> Result<(), PlotError> {
    let n = estimates.len();
    let mut legend = Vec::new();
    if !walls.is_empty() {
        legend.push(LegendEntry {
            name: "walls".into(),
            glyph: Glyph::Line(WALL_GREY, 4),
        });
    }
    if let Some(r) = reference {
        legend.push(LegendEntry {
            name: r.name.into(),
            glyph: Glyph::Line(BLACK, 1),
        });
    }
    for (i, e) in estimates.iter().enumerate() {
        legend.push(LegendEntry {
            name: e.name.into(),
            glyph: Glyph::Line(colour(i), layered_width(i, n)),
        });
    }
    legend.extend(markers.iter().map(marker_entry));
    let area = with_legend(area, &legend)?;
    let mut chart = build_chart(&area, "x [m]", "y [m]", |size| equal_aspect(x, y, size))?;
    draw_walls(&mut chart, walls)?;
    let xy = |s: &TrajectorySeries<'_>| {
        s.trajectory
            .iter()
            .map(|p| (p.pose.x, p.pose.y))
            .collect::<Vec<_>>()
    };
    for (i, e) in estimates.iter().enumerate() {
        draw_series(
            &mut chart,
            xy(e).into_iter(),
            colour(i),
            layered_width(i, n),
        )?;
    }
    if let Some(r) = reference {
        draw_series(&mut chart, xy(r).into_iter(), BLACK, 1)?;
    }
    for m in markers {
        let (r, g, b) = m.colour;
        draw_markers(
            &mut chart,
            m.points.iter().copied(),
            RGBColor(r, g, b),
            m.shape,
        )?;
    }
    Ok(())
}

/// The legend entry of a marker set.
pub(super) fn marker_entry<P>(m: &Markers<'_, P>) -> LegendEntry {
    let (r, g, b) = m.colour;
    LegendEntry {
        name: m.name.into(),
        glyph: Glyph::Marker(RGBColor(r, g, b), m.shape),
    }
}
