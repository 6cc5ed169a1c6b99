//! What the plots share: the colours and line widths, the chart frame sizes, data ranges
//! that include every finite point, markers, and the legend drawn above each chart.

use super::{MarkerShape, PlotError, PlotOptions};
use plotters::coord::ranged1d::ValueFormatter;
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::io::Write;
use std::ops::Range;

/// Colours of the estimates, in order (matplotlib's `tab10`); the reference is black.
pub(super) const PALETTE: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

/// Blank border around the chart (px).
pub(super) const MARGIN: u32 = 20;
/// Height of the x-axis label area (px).
pub(super) const X_LABEL_AREA: u32 = 50;
/// Width of the y-axis label area (px).
pub(super) const Y_LABEL_AREA: u32 = 70;
/// Font size of the title (px).
pub(super) const TITLE_SIZE: u32 = 24;
/// Font size of axis descriptions and the legend (px).
pub(super) const LABEL_SIZE: u32 = 18;
/// Font size of the tick labels (px).
pub(super) const TICK_SIZE: u32 = 15;
/// Smallest width and height the frame above leaves room for (px).
pub(super) const MIN_SIZE: u32 = 2 * MARGIN + Y_LABEL_AREA + X_LABEL_AREA + 2 * TITLE_SIZE;

/// Colour of the `index`-th estimate.
pub(super) fn colour(index: usize) -> RGBColor {
    PALETTE[index % PALETTE.len()]
}

/// Fails unless the image leaves room for the chart frame.
pub(super) fn check_size(options: &PlotOptions) -> Result<(), PlotError> {
    if options.width < MIN_SIZE || options.height < MIN_SIZE {
        return Err(PlotError::TooSmall {
            width: options.width,
            height: options.height,
            min: MIN_SIZE,
        });
    }
    Ok(())
}

/// The smallest range holding every finite value, widened by 5 % on each side (or ±0.5
/// around a single value); `None` if there is no finite value.
pub(super) fn padded_range(values: impl Iterator<Item = f64>) -> Option<Range<f64>> {
    let (lo, hi) = values
        .filter(|v| v.is_finite())
        .fold(None, |acc: Option<(f64, f64)>, v| {
            Some(acc.map_or((v, v), |(lo, hi)| (lo.min(v), hi.max(v))))
        })?;
    let pad = if hi > lo { 0.05 * (hi - lo) } else { 0.5 };
    Some(lo - pad..hi + pad)
}

/// The chart both plots draw on: f64 data coordinates on an SVG image.
pub(super) type Chart<'a, 'b> =
    ChartContext<'a, SVGBackend<'b>, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// The pixel size of the data area of a chart built by [`build_chart`] on an area of
/// `(width, height)` px.
pub(super) fn data_area_size((width, height): (u32, u32)) -> (u32, u32) {
    (
        width.saturating_sub(2 * MARGIN + Y_LABEL_AREA).max(1),
        height.saturating_sub(2 * MARGIN + X_LABEL_AREA).max(1),
    )
}

/// `x` and `y` widened about their centres so that one metre spans as many pixels
/// along x as along y in a data area of `(width, height)` px.
pub(super) fn equal_aspect(
    x: Range<f64>,
    y: Range<f64>,
    (width, height): (u32, u32),
) -> (Range<f64>, Range<f64>) {
    let (w, h) = (f64::from(width), f64::from(height));
    let per_px = ((x.end - x.start) / w).max((y.end - y.start) / h);
    let around = |r: &Range<f64>, px: f64| {
        let centre = 0.5 * (r.start + r.end);
        centre - 0.5 * per_px * px..centre + 0.5 * per_px * px
    };
    (around(&x, w), around(&y, h))
}

/// The image with an optional title, and a chart with a light grid and axis
/// descriptions on the rest of it; `ranges` gets the data area's pixel size and returns
/// the axis ranges.
pub(super) fn build_chart<'a, 'b>(
    area: &'a DrawingArea<SVGBackend<'b>, Shift>,
    x_desc: &str,
    y_desc: &str,
    ranges: impl FnOnce((u32, u32)) -> (Range<f64>, Range<f64>),
) -> Result<Chart<'a, 'b>, PlotError> {
    let (x, y) = ranges(data_area_size(area.dim_in_pixel()));
    let mut chart = ChartBuilder::on(area)
        .margin(MARGIN)
        .x_label_area_size(X_LABEL_AREA)
        .y_label_area_size(Y_LABEL_AREA)
        .build_cartesian_2d(x, y)?;
    chart
        .configure_mesh()
        .x_desc(x_desc)
        .y_desc(y_desc)
        .axis_desc_style(("sans-serif", LABEL_SIZE))
        .label_style(("sans-serif", TICK_SIZE))
        .x_label_formatter(&tick_label)
        .y_label_formatter(&tick_label)
        .max_light_lines(0)
        .draw()?;
    Ok(chart)
}

/// A tick label as `plotters` prints it, but never `-0.0` for a tick at zero.
fn tick_label(value: &f64) -> String {
    let text = RangedCoordf64::format(value);
    match text.strip_prefix('-') {
        Some(unsigned) if unsigned.parse::<f64>() == Ok(0.0) => unsigned.to_owned(),
        _ => text,
    }
}

/// A series' stroke width (px) when it is the `index`-th of `count` drawn in order: the
/// last 2 px, each earlier one 1 px wider (up to 5 px), so that a series drawn over an
/// equal one leaves it showing on both sides.
pub(super) fn layered_width(index: usize, count: usize) -> u32 {
    let above = count.saturating_sub(index + 1);
    2 + u32::try_from(above.min(3)).unwrap_or(3)
}

/// What a legend entry shows.
#[derive(Debug, Clone, Copy)]
pub(super) enum Glyph {
    /// A line of this colour and width.
    Line(RGBColor, u32),
    /// A marker.
    Marker(RGBColor, MarkerShape),
}

/// One legend entry.
#[derive(Debug, Clone)]
pub(super) struct LegendEntry {
    /// The name shown.
    pub name: String,
    /// What is drawn before it.
    pub glyph: Glyph,
}

/// Size of a marker (px).
const MARKER_SIZE: i32 = 6;

/// Draws one series as a single line (one SVG `<polyline>`); non-finite points are
/// skipped.
pub(super) fn draw_series(
    chart: &mut Chart<'_, '_>,
    points: impl Iterator<Item = (f64, f64)>,
    colour: RGBColor,
    width: u32,
) -> Result<(), PlotError> {
    let finite = points.filter(|(x, y)| x.is_finite() && y.is_finite());
    chart.draw_series(LineSeries::new(finite, colour.stroke_width(width)))?;
    Ok(())
}

/// Draws a marker of `shape` at each finite point.
pub(super) fn draw_markers(
    chart: &mut Chart<'_, '_>,
    points: impl Iterator<Item = (f64, f64)>,
    colour: RGBColor,
    shape: MarkerShape,
) -> Result<(), PlotError> {
    let finite: Vec<(f64, f64)> = points
        .filter(|(x, y)| x.is_finite() && y.is_finite())
        .collect();
    let style = colour.stroke_width(2);
    match shape {
        MarkerShape::Cross => {
            chart.draw_series(finite.iter().map(|&p| Cross::new(p, MARKER_SIZE, style)))?;
        }
        MarkerShape::Circle => {
            chart.draw_series(finite.iter().map(|&p| Circle::new(p, MARKER_SIZE, style)))?;
        }
        MarkerShape::Triangle => {
            chart.draw_series(
                finite
                    .iter()
                    .map(|&p| TriangleMarker::new(p, MARKER_SIZE, style)),
            )?;
        }
        MarkerShape::Dot => {
            chart.draw_series(finite.iter().map(|&p| Circle::new(p, 2, colour.filled())))?;
        }
    }
    Ok(())
}

/// Colour of walls.
pub(super) const WALL_GREY: RGBColor = RGBColor(150, 150, 150);

/// Draws `walls` as thick grey segments.
pub(super) fn draw_walls(
    chart: &mut Chart<'_, '_>,
    walls: &[super::Wall],
) -> Result<(), PlotError> {
    for w in walls {
        let ends = w.iter().map(|p| (p[0], p[1]));
        chart.draw_series(LineSeries::new(ends, WALL_GREY.stroke_width(4)))?;
    }
    Ok(())
}

/// Height of one row of legend entries (px).
const LEGEND_ROW: u32 = LABEL_SIZE + 10;

/// Width of an entry's glyph and the gaps around it (px).
const LEGEND_GLYPH: u32 = 24;

/// Draws `entries` in rows across the top of `area`, above the chart (so that the legend
/// never covers data), and returns the area left below it for the chart.
pub(super) fn with_legend<'b>(
    area: &DrawingArea<SVGBackend<'b>, Shift>,
    entries: &[LegendEntry],
) -> Result<DrawingArea<SVGBackend<'b>, Shift>, PlotError> {
    if entries.is_empty() {
        return Ok(area.clone());
    }
    let font = ("sans-serif", LABEL_SIZE).into_font();
    let measured = font.clone().color(&BLACK);
    let (width, _) = area.dim_in_pixel();
    let usable = width.saturating_sub(2 * MARGIN + Y_LABEL_AREA).max(1);
    // Lay the entries out left to right, wrapping into new rows.
    let mut placed = Vec::with_capacity(entries.len());
    let (mut x, mut row) = (0u32, 0u32);
    for e in entries {
        let text_width = area
            .estimate_text_size(&e.name, &measured)
            .map_or(10 * e.name.len() as u32, |(w, _)| w);
        let needed = LEGEND_GLYPH + 6 + text_width + 18;
        if x > 0 && x + needed > usable {
            x = 0;
            row += 1;
        }
        placed.push((x, row, e));
        x += needed;
    }
    let height = (row + 1) * LEGEND_ROW + 6;
    let (strip, rest) = area.split_vertically(height);
    let left = i32::try_from(MARGIN + Y_LABEL_AREA).unwrap_or(0);
    for (x, row, e) in placed {
        let x0 = left + i32::try_from(x).unwrap_or(0);
        let y_mid = i32::try_from(row * LEGEND_ROW + LEGEND_ROW / 2 + 4).unwrap_or(0);
        let glyph_end = x0 + LEGEND_GLYPH as i32;
        match e.glyph {
            Glyph::Line(colour, width) => {
                strip.draw(&PathElement::new(
                    vec![(x0, y_mid), (glyph_end, y_mid)],
                    colour.stroke_width(width),
                ))?;
            }
            Glyph::Marker(colour, shape) => {
                let centre = (x0 + LEGEND_GLYPH as i32 / 2, y_mid);
                let style = colour.stroke_width(2);
                match shape {
                    MarkerShape::Cross => strip.draw(&Cross::new(centre, MARKER_SIZE, style))?,
                    MarkerShape::Circle => strip.draw(&Circle::new(centre, MARKER_SIZE, style))?,
                    MarkerShape::Triangle => {
                        strip.draw(&TriangleMarker::new(centre, MARKER_SIZE, style))?
                    }
                    MarkerShape::Dot => strip.draw(&Circle::new(centre, 3, colour.filled()))?,
                }
            }
        }
        let text_style = font
            .clone()
            .color(&BLACK)
            .pos(Pos::new(HPos::Left, VPos::Center));
        strip.draw(&Text::new(
            e.name.clone(),
            (glyph_end + 6, y_mid),
            text_style,
        ))?;
    }
    Ok(rest)
}

/// Renders an SVG image of `options`' size with `draw` (which gets the area below the
/// title) and writes it to `writer`.
pub(super) fn render<W: Write>(
    mut writer: W,
    options: &PlotOptions,
    draw: impl FnOnce(&DrawingArea<SVGBackend<'_>, Shift>) -> Result<(), PlotError>,
) -> Result<(), PlotError> {
    check_size(options)?;
    let mut svg = String::new();
    {
        let root =
            SVGBackend::with_string(&mut svg, (options.width, options.height)).into_drawing_area();
        root.fill(&WHITE)?;
        let area = if options.title.is_empty() {
            root.clone()
        } else {
            root.titled(&options.title, ("sans-serif", TITLE_SIZE))?
        };
        draw(&area)?;
        root.present()?;
    }
    writer.write_all(svg.as_bytes())?;
    writer.flush()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn equal_aspect_gives_equal_metres_per_pixel() {
        let (x, y) = equal_aspect(0.0..10.0, -1.0..1.0, (500, 250));
        let per_px_x = (x.end - x.start) / 500.0;
        let per_px_y = (y.end - y.start) / 250.0;
        assert!((per_px_x - per_px_y).abs() < 1e-12);
        assert_eq!(x, 0.0..10.0);
        assert!((0.5 * (y.start + y.end)).abs() < 1e-12);
    }

    #[test]
    fn tick_labels_have_no_negative_zero() {
        assert_eq!(tick_label(&-1e-17), "0.0");
        assert_eq!(tick_label(&-0.5), "-0.5");
        assert_eq!(tick_label(&2.0), "2.0");
    }

    #[test]
    fn padded_range_ignores_non_finite_values() {
        let r = padded_range([1.0, f64::NAN, 3.0, f64::INFINITY].into_iter()).unwrap();
        assert!((r.start - 0.9).abs() < 1e-12 && (r.end - 3.1).abs() < 1e-12);
        assert_eq!(padded_range([2.0].into_iter()), Some(1.5..2.5));
        assert_eq!(padded_range([f64::NAN].into_iter()), None);
    }
}
