//! The SVG plots parse as XML, hold one polyline per series and name every series in
//! the legend; several panels share one figure.

mod svg_support;

use ekf_cli::plot::{
    plot_errors_over_time, plot_figure, plot_trajectories, Panel, PlotError, PlotOptions,
    TimeSeries, TrajectorySeries,
};
use ekf_cli::trajectory::{StampedPose, Trajectory};
use ekf_core::Pose2;
use svg_support::inspect_svg;

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
    let (polylines, texts) = inspect_svg(&svg);
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
    let (polylines, texts) = inspect_svg(&svg);
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

/// A straight trajectory of `n` poses 10 cm and 100 ms apart, with the given slope.
fn line(n: u64, slope: f64) -> Trajectory {
    (0..n)
        .map(|i| {
            let x = i as f64 * 0.1;
            StampedPose::new(i * 100_000_000, Pose2::new(x, slope * x, 0.0))
        })
        .collect()
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
            walls: &[[[-1.0, -1.0], [6.0, -1.0]], [[6.0, -1.0], [6.0, 4.0]]],
            markers: &[],
        },
        Panel::ErrorsOverTime {
            title: "",
            series: &series,
            y_desc: "e [m]",
            markers: &[],
        },
        Panel::ErrorsOverTime {
            title: "third",
            series: &series,
            y_desc: "e [m]",
            markers: &[],
        },
    ];
    let mut svg = Vec::new();
    let options = PlotOptions {
        title: "all".into(),
        width: 1000,
        height: 800,
    };
    plot_figure(&mut svg, &panels, 2, &options).unwrap();
    let (lines, texts) = inspect_svg(&svg);
    // The trajectories and error series (the walls are two-point segments, not counted
    // here, and have one legend entry).
    assert_eq!(lines, 4);
    assert_eq!(texts.iter().filter(|t| *t == "walls").count(), 1);
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
        markers: &[],
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
        markers: &[],
    };
    // 900 px across is enough for one chart, not for ten side by side.
    plot_figure(Vec::new(), &[panel], 1, &options).unwrap();
    let err = plot_figure(Vec::new(), &[panel; 10], 10, &options);
    assert!(matches!(err, Err(PlotError::TooSmall { .. })), "{err:?}");
}
