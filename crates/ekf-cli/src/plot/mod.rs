//! SVG plots of trajectories and of errors over time, drawn with `plotters`' SVG backend.
//!
//! No system fonts are needed: text is written as SVG `<text>` elements (the viewer
//! picks a sans-serif font) and laid out with `plotters`' built-in size estimate.

mod axes;
mod error_plot;
mod figure;
mod trajectory_plot;

pub use error_plot::{plot_errors_over_time, TimeSeries};
pub use figure::{plot_figure, Panel};
pub use trajectory_plot::{plot_trajectories, TrajectorySeries, Wall};

/// The shape of an event marker.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MarkerShape {
    /// ×
    Cross,
    /// ○
    Circle,
    /// △
    Triangle,
    /// A small filled dot.
    Dot,
}

/// Named event markers drawn over a chart's lines: `P` is `(x, y)` in metres on a
/// trajectory chart, `(stamp in ns, value)` on a chart over time.
#[derive(Debug, Clone, Copy)]
pub struct Markers<'a, P> {
    /// Legend name.
    pub name: &'a str,
    /// Where the markers go.
    pub points: &'a [P],
    /// Their shape.
    pub shape: MarkerShape,
    /// Their colour, `(r, g, b)`.
    pub colour: (u8, u8, u8),
}

/// Size and title of a plot.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PlotOptions {
    /// Title above the chart (empty: none).
    pub title: String,
    /// Width of the image (px).
    pub width: u32,
    /// Height of the image (px).
    pub height: u32,
}

impl Default for PlotOptions {
    fn default() -> Self {
        Self {
            title: String::new(),
            width: 900,
            height: 700,
        }
    }
}

/// Why a plot could not be made.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// No series has a finite point.
    #[error("nothing to plot: no series has a finite point")]
    NoData,
    /// The image is too small for the chart's margins and labels.
    #[error("plot size {width}x{height} px is too small (at least {min}x{min})")]
    TooSmall {
        /// Requested width (px).
        width: u32,
        /// Requested height (px).
        height: u32,
        /// Smallest usable width and height (px).
        min: u32,
    },
    /// `plotters` failed while drawing.
    #[error("drawing the plot failed: {0}")]
    Draw(String),
    /// Writing the SVG failed.
    #[error("writing the plot failed: {0}")]
    Io(#[from] std::io::Error),
}

impl<E: std::error::Error + Send + Sync> From<plotters::drawing::DrawingAreaErrorKind<E>>
    for PlotError
{
    fn from(e: plotters::drawing::DrawingAreaErrorKind<E>) -> Self {
        Self::Draw(e.to_string())
    }
}
