//! Several charts in one SVG image, on a grid: e.g. the paper's Fig. 9 (trajectories)
//! next to its Fig. 10 (x and y errors over time).

use super::axes::{render, LABEL_SIZE, MIN_SIZE};
use super::error_plot::{draw_errors, time_ranges, TimeRanges};
use super::trajectory_plot::{draw_trajectories, trajectory_ranges};
use super::{PlotError, PlotOptions, TimeSeries, TrajectorySeries};
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
    },
}

/// A panel with its data ranges, computed before anything is drawn.
enum Prepared<'p, 'a> {
    Trajectories {
        ranges: (Range<f64>, Range<f64>),
        reference: Option<&'p TrajectorySeries<'a>>,
        estimates: &'a [TrajectorySeries<'a>],
    },
    Errors {
        ranges: TimeRanges,
        series: &'a [TimeSeries<'a>],
        y_desc: &'a str,
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
                    ..
                } => Ok(Prepared::Trajectories {
                    ranges: trajectory_ranges(reference.as_ref(), estimates)?,
                    reference: reference.as_ref(),
                    estimates,
                }),
                Panel::ErrorsOverTime { series, y_desc, .. } => Ok(Prepared::Errors {
                    ranges: time_ranges(series)?,
                    series,
                    y_desc,
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
                } => draw_trajectories(area, ranges, reference, estimates)?,
                Prepared::Errors {
                    ranges,
                    series,
                    y_desc,
                } => draw_errors(area, &ranges, series, y_desc)?,
            }
        }
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::trajectory::Trajectory;
    use ekf_core::Pose2;

    fn line(n: u64, slope: f64) -> Trajectory {
        (0..n)
            .map(|i| {
                let x = i as f64 * 0.1;
                crate::trajectory::StampedPose::new(i * 100_000_000, Pose2::new(x, slope * x, 0.0))
            })
            .collect()
    }

    /// (data lines, texts) of an SVG: polylines of more than two points.
    fn inspect(svg: &[u8]) -> (usize, Vec<String>) {
        let text = std::str::from_utf8(svg).unwrap();
        let doc = roxmltree::Document::parse(text).unwrap();
        let lines = doc
            .descendants()
            .filter(|n| n.has_tag_name("polyline"))
            .filter(|n| {
                n.attribute("points")
                    .unwrap_or("")
                    .split_whitespace()
                    .count()
                    > 2
            })
            .count();
        let texts = doc
            .descendants()
            .filter(|n| n.has_tag_name("text"))
            .filter_map(|n| n.text().map(|t| t.trim().to_owned()))
            .collect();
        (lines, texts)
    }

    #[test]
    fn panels_on_a_grid_in_one_svg() {
        let (truth, est) = (line(20, 0.0), line(20, 0.1));
        let errors: Vec<(u64, f64)> = (0..20).map(|i| (i * 100_000_000, i as f64)).collect();
        let estimates = [TrajectorySeries {
            name: "est",
            trajectory: &est,
        }];
        let series = [TimeSeries {
            name: "err",
            points: &errors,
        }];
        let panels = [
            Panel::Trajectories {
                title: "paths",
                reference: Some(TrajectorySeries {
                    name: "truth",
                    trajectory: &truth,
                }),
                estimates: &estimates,
            },
            Panel::ErrorsOverTime {
                title: "",
                series: &series,
                y_desc: "e [m]",
            },
            Panel::ErrorsOverTime {
                title: "third",
                series: &series,
                y_desc: "e [m]",
            },
        ];
        let mut svg = Vec::new();
        let options = PlotOptions {
            title: "all".into(),
            width: 1000,
            height: 800,
        };
        plot_figure(&mut svg, &panels, 2, &options).unwrap();
        let (lines, texts) = inspect(&svg);
        assert_eq!(lines, 4);
        for t in ["all", "paths", "third", "truth", "est", "err", "e [m]"] {
            assert!(texts.iter().any(|x| x == t), "{t}: {texts:?}");
        }
        assert_eq!(texts.iter().filter(|t| *t == "err").count(), 2);
    }

    #[test]
    fn empty_panels_and_small_cells_are_errors() {
        let options = PlotOptions::default();
        assert!(matches!(
            plot_figure(Vec::new(), &[], 2, &options),
            Err(PlotError::NoData)
        ));
        let empty = [TimeSeries {
            name: "none",
            points: &[],
        }];
        let panel = Panel::ErrorsOverTime {
            title: "",
            series: &empty,
            y_desc: "",
        };
        assert!(matches!(
            plot_figure(Vec::new(), &[panel], 1, &options),
            Err(PlotError::NoData)
        ));
        let points = [(0, 1.0), (1, 2.0)];
        let some = [TimeSeries {
            name: "some",
            points: &points,
        }];
        let panel = Panel::ErrorsOverTime {
            title: "",
            series: &some,
            y_desc: "",
        };
        // 900 px across is enough for one chart, not for ten side by side.
        plot_figure(Vec::new(), &[panel], 1, &options).unwrap();
        let err = plot_figure(Vec::new(), &[panel; 10], 10, &options);
        assert!(matches!(err, Err(PlotError::TooSmall { .. })), "{err:?}");
    }
}
