//! The SVG plots parse as XML, hold one polyline per series and name every series in
//! the legend.

use ekf_cli::plot::{
    plot_errors_over_time, plot_trajectories, PlotError, PlotOptions, TimeSeries, TrajectorySeries,
};
use ekf_cli::trajectory::Trajectory;
use ekf_core::Pose2;

/// A circle of radius 5 m sampled at 10 Hz, shifted by `(dx, dy)`.
fn circle(dx: f64, dy: f64) -> Trajectory {
    let mut t = Trajectory::new();
    for k in 0..100_u64 {
        let a = k as f64 * 0.0628;
        t.push(
            1_700_000_000_000_000_000 + k * 100_000_000,
            Pose2::new(5.0 * a.cos() + dx, 5.0 * a.sin() + dy, a + 1.57),
        );
    }
    t
}

/// Parses the SVG and returns (number of data lines, all `<text>` contents). A data line
/// is a `<polyline>` of more than two points (axes and ticks are two-point polylines).
fn inspect(svg: &[u8]) -> (usize, Vec<String>) {
    let text = std::str::from_utf8(svg).expect("SVG is UTF-8");
    let doc = roxmltree::Document::parse(text).expect("SVG is well-formed XML");
    assert_eq!(doc.root_element().tag_name().name(), "svg");
    let polylines = doc
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
    (polylines, texts)
}

#[test]
fn trajectory_plot_has_a_line_and_a_legend_entry_per_trajectory() {
    let (truth, odom, ekf) = (circle(0.0, 0.0), circle(0.4, -0.2), circle(0.05, 0.0));
    let mut svg = Vec::new();
    plot_trajectories(
        &mut svg,
        Some(TrajectorySeries {
            name: "reference",
            trajectory: &truth,
        }),
        &[
            TrajectorySeries {
                name: "odometry only",
                trajectory: &odom,
            },
            TrajectorySeries {
                name: "EKF laser + compass",
                trajectory: &ekf,
            },
        ],
        &PlotOptions {
            title: "Fig. 9 <sim>".into(),
            ..PlotOptions::default()
        },
    )
    .unwrap();
    let (polylines, texts) = inspect(&svg);
    assert_eq!(polylines, 3);
    for name in [
        "reference",
        "odometry only",
        "EKF laser + compass",
        "Fig. 9 <sim>",
        "x [m]",
        "y [m]",
    ] {
        assert!(
            texts.iter().any(|t| t == name),
            "{name} missing in {texts:?}"
        );
    }
}

#[test]
fn error_plot_has_a_line_and_a_legend_entry_per_series() {
    let dx: Vec<(u64, f64)> = (0..50)
        .map(|k| (1_700_000_000_000_000_000 + k * 100_000_000, 0.01 * k as f64))
        .collect();
    let dy: Vec<(u64, f64)> = dx.iter().map(|&(t, v)| (t, -v)).collect();
    let series = [
        TimeSeries {
            name: "x error",
            points: &dx,
        },
        TimeSeries {
            name: "y error",
            points: &dy,
        },
    ];
    let mut svg = Vec::new();
    plot_errors_over_time(&mut svg, &series, "error [m]", &PlotOptions::default()).unwrap();
    let (polylines, texts) = inspect(&svg);
    assert_eq!(polylines, 2);
    for name in ["x error", "y error", "time [s]", "error [m]"] {
        assert!(
            texts.iter().any(|t| t == name),
            "{name} missing in {texts:?}"
        );
    }
}

#[test]
fn plots_of_nothing_or_too_small_are_errors() {
    let empty = Trajectory::new();
    let none = TrajectorySeries {
        name: "empty",
        trajectory: &empty,
    };
    let err = plot_trajectories(Vec::new(), Some(none), &[], &PlotOptions::default());
    assert!(matches!(err, Err(PlotError::NoData)));
    let err = plot_errors_over_time(Vec::new(), &[], "m", &PlotOptions::default());
    assert!(matches!(err, Err(PlotError::NoData)));
    let tiny = PlotOptions {
        width: 50,
        height: 50,
        ..PlotOptions::default()
    };
    let truth = circle(0.0, 0.0);
    let some = TrajectorySeries {
        name: "truth",
        trajectory: &truth,
    };
    let err = plot_trajectories(Vec::new(), Some(some), &[], &tiny);
    assert!(matches!(err, Err(PlotError::TooSmall { .. })), "{err:?}");
}
