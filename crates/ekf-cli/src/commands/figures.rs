//! The pictures of `ekf replay --svg` and `ekf evaluate --svg`: the trajectory over the
//! map with the reference, and the error over time; for a replay, markers where lines
//! were refused, the compass rejected, the filter lost or relocalized.

use crate::eval::{ape, AlignMode, ApeOptions, EvalError};
use crate::plot::{
    plot_figure, MarkerShape, Markers, Panel, PlotError, PlotOptions, TimeSeries, TrajectorySeries,
    Wall,
};
use crate::replay::{ReplayEvent, ReplayOutcome};
use crate::trajectory::{StampedPose, Trajectory};
use lrf_lines::{LineMap, MapSegment};
use std::io::Write;
use std::path::Path;

/// Writes the picture `draw` makes to the file `path`.
pub fn write_svg_file(
    path: &Path,
    draw: impl FnOnce(&mut std::io::BufWriter<std::fs::File>) -> Result<(), FigureError>,
) -> Result<(), FigureError> {
    let in_file = |source| FigureError::File {
        path: path.display().to_string(),
        source,
    };
    let file = std::fs::File::create(path).map_err(|e| in_file(PlotError::Io(e)))?;
    let mut writer = std::io::BufWriter::new(file);
    match draw(&mut writer) {
        Err(FigureError::Plot(e)) => Err(in_file(e)),
        other => other,
    }
}

/// Size of a two-chart figure (px): the trajectory beside the errors.
pub const FIGURE_SIZE: (u32, u32) = (1500, 650);

/// Map segments (a [`LineMap`]'s, a simulated room's) as plot walls.
pub fn walls_of(segments: &[MapSegment]) -> Vec<Wall> {
    segments
        .iter()
        .map(|w| [[w.start.x, w.start.y], [w.end.x, w.end.y]])
        .collect()
}

/// Why a picture could not be drawn.
#[derive(Debug, thiserror::Error)]
pub enum FigureError {
    /// The SVG file could not be created or written.
    #[error("{path}: {source}")]
    File {
        /// The SVG file.
        path: String,
        /// What failed.
        source: PlotError,
    },
    /// Drawing or writing failed.
    #[error(transparent)]
    Plot(#[from] PlotError),
    /// The trajectories could not be compared.
    #[error(transparent)]
    Eval(#[from] EvalError),
}

/// Marker shape and colour of each event kind.
fn marker_style(event: ReplayEvent) -> (MarkerShape, (u8, u8, u8)) {
    match event {
        ReplayEvent::LinesRefused => (MarkerShape::Dot, (148, 103, 189)),
        ReplayEvent::CompassRejected => (MarkerShape::Triangle, (255, 127, 14)),
        ReplayEvent::Lost => (MarkerShape::Cross, (214, 39, 40)),
        ReplayEvent::Relocalized => (MarkerShape::Circle, (44, 160, 44)),
    }
}

/// One marker set per event kind, styled by [`marker_style`].
fn event_markers<P>(events: &[(ReplayEvent, Vec<P>)]) -> Vec<Markers<'_, P>> {
    events
        .iter()
        .map(|(kind, points)| {
            let (shape, colour) = marker_style(*kind);
            Markers {
                name: kind.name(),
                points,
                shape,
                colour,
            }
        })
        .collect()
}

/// The pose of `trajectory` at or just before `t_ns` (the first pose before it starts).
fn pose_at(trajectory: &Trajectory, t_ns: u64) -> Option<(f64, f64)> {
    let poses = &trajectory.samples;
    let i = poses.partition_point(|p| p.t_ns <= t_ns).saturating_sub(1);
    poses.get(i).map(|p| (p.pose.x, p.pose.y))
}

/// The value of `series` at or just before `t_ns`.
fn value_at(series: &[(u64, f64)], t_ns: u64) -> Option<f64> {
    let i = series.partition_point(|p| p.0 <= t_ns).saturating_sub(1);
    series.get(i).map(|p| p.1)
}

/// Draws a replay as one SVG: the estimate over the map's walls with the log's
/// reference (a thin black line on top), and the position error against the reference
/// over time with the filter's own 2σ position bound `2·√(σx² + σy²)` — or, without a
/// reference, that bound alone. Events are marked on both charts at their stamps.
pub fn replay_svg<W: Write>(
    outcome: &ReplayOutcome,
    map: Option<&LineMap>,
    title: &str,
    writer: W,
) -> Result<(), FigureError> {
    let walls = map.map(|m| walls_of(&m.segments)).unwrap_or_default();
    let estimate = [TrajectorySeries {
        name: "estimate",
        trajectory: &outcome.trajectory,
    }];
    let reference = (!outcome.reference.is_empty()).then_some(TrajectorySeries {
        name: "reference",
        trajectory: &outcome.reference,
    });
    let errors: Vec<(u64, f64)> = match reference {
        Some(_) => ape(
            &outcome.reference,
            &outcome.trajectory,
            &ApeOptions::default(),
        )?
        .errors
        .iter()
        .map(|e| (e.t_ns, e.translation))
        .collect(),
        None => Vec::new(),
    };
    let bound: Vec<(u64, f64)> = outcome
        .trajectory
        .iter()
        .zip(&outcome.covariances)
        .map(|(p, c)| (p.t_ns, 2.0 * (c[(0, 0)] + c[(1, 1)]).max(0.0).sqrt()))
        .collect();
    // Events on the trajectory at the estimate's position, on the error chart at the
    // error's value (or the bound's, without a reference).
    let on_time = if errors.is_empty() { &bound } else { &errors };
    let mut on_map: Vec<(ReplayEvent, Vec<(f64, f64)>)> = Vec::new();
    let mut over_time: Vec<(ReplayEvent, Vec<(u64, f64)>)> = Vec::new();
    for kind in ReplayEvent::ALL {
        let stamps = outcome.events.iter().filter(|e| e.1 == kind).map(|e| e.0);
        let xy: Vec<(f64, f64)> = stamps
            .clone()
            .filter_map(|t| pose_at(&outcome.trajectory, t))
            .collect();
        let tv: Vec<(u64, f64)> = stamps
            .filter_map(|t| value_at(on_time, t).map(|v| (t, v)))
            .collect();
        if !xy.is_empty() {
            on_map.push((kind, xy));
            over_time.push((kind, tv));
        }
    }
    let map_markers = event_markers(&on_map);
    let time_markers = event_markers(&over_time);
    // The bound first, so that the error is drawn over it.
    let mut series = vec![TimeSeries {
        name: "2σ (filter)",
        points: &bound,
    }];
    if !errors.is_empty() {
        series.push(TimeSeries {
            name: "position error",
            points: &errors,
        });
    }
    let panels = [
        Panel::Trajectories {
            title: "Trajectory",
            reference,
            estimates: &estimate,
            walls: &walls,
            markers: &map_markers,
        },
        Panel::ErrorsOverTime {
            title: if errors.is_empty() {
                "Position uncertainty (no reference in the log)"
            } else {
                "Position error against the reference"
            },
            series: &series,
            y_desc: "m",
            markers: &time_markers,
        },
    ];
    let options = PlotOptions {
        title: title.to_owned(),
        width: FIGURE_SIZE.0,
        height: FIGURE_SIZE.1,
    };
    Ok(plot_figure(writer, &panels, 2, &options)?)
}

/// Draws an evaluation as one SVG, as `evo_ape --plot` shows it: the estimate (aligned
/// first when `align`, as the numbers are) with the reference in the x–y plane, and the
/// position and heading errors of the matched poses over time.
pub fn evaluation_svg<W: Write>(
    estimate: &Trajectory,
    reference: &Trajectory,
    align: bool,
    title: &str,
    writer: W,
) -> Result<(), FigureError> {
    let mut options = ApeOptions::default();
    if align {
        options.alignment.mode = AlignMode::Rigid;
    }
    let result = ape(reference, estimate, &options)?;
    let aligned: Trajectory = match &result.summary.alignment {
        Some(a) => estimate
            .iter()
            .map(|p| StampedPose::new(p.t_ns, a.apply(&p.pose)))
            .collect(),
        None => estimate.clone(),
    };
    let position: Vec<(u64, f64)> = result
        .errors
        .iter()
        .map(|e| (e.t_ns, e.translation))
        .collect();
    let heading: Vec<(u64, f64)> = result
        .errors
        .iter()
        .map(|e| (e.t_ns, e.heading_deg))
        .collect();
    let estimates = [TrajectorySeries {
        name: if align {
            "estimate (aligned)"
        } else {
            "estimate"
        },
        trajectory: &aligned,
    }];
    let position = [TimeSeries {
        name: "position error [m]",
        points: &position,
    }];
    let heading = [TimeSeries {
        name: "heading error [deg]",
        points: &heading,
    }];
    let panels = [
        Panel::Trajectories {
            title: "Trajectories",
            reference: Some(TrajectorySeries {
                name: "reference",
                trajectory: reference,
            }),
            estimates: &estimates,
            walls: &[],
            markers: &[],
        },
        Panel::ErrorsOverTime {
            title: "Position error (APE)",
            series: &position,
            y_desc: "m",
            markers: &[],
        },
        Panel::ErrorsOverTime {
            title: "Heading error",
            series: &heading,
            y_desc: "deg",
            markers: &[],
        },
    ];
    let options = PlotOptions {
        title: title.to_owned(),
        width: FIGURE_SIZE.0,
        height: 2 * FIGURE_SIZE.1,
    };
    Ok(plot_figure(writer, &panels, 2, &options)?)
}
