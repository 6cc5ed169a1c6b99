//! `ekf compare` as a library: the paper's four configurations on one synthetic log
//! (see `compare_common`), their accuracy, the combined SVG, and the failure cases.

mod compare_common;
mod svg_support;

use compare_common::{write_room_bag, BagContents};
use ekf_cli::commands::compare::{
    compare, render_svg, write_svg, CompareError, CompareOptions, Comparison, ModeOutcome,
};
use ekf_cli::config::Config;
use ekf_cli::replay::Mode;
use std::path::Path;
use std::sync::OnceLock;
use svg_support::inspect_svg;

/// The comparison of the full bag, computed once for the tests that share it.
fn full() -> &'static Comparison {
    static FULL: OnceLock<Comparison> = OnceLock::new();
    FULL.get_or_init(|| {
        let dir = tempfile::tempdir().unwrap();
        let log = dir.path().join("room.mcap");
        write_room_bag(&log, BagContents::default());
        compare(&log, &on_the_mark(), &CompareOptions::default()).unwrap()
    })
}

/// The defaults, told that the robot starts exactly where it does (to 1 mm and 0.1°):
/// the first-scan map is placed there, and a looser prior would have the filter hedge
/// against a placement error that this log does not have.
fn on_the_mark() -> Config {
    let mut config = Config::default();
    config.initial.sigma_xy = 0.001;
    config.initial.sigma_theta = 0.1_f64.to_radians();
    config
}

fn rmse(c: &Comparison, mode: &str) -> f64 {
    c.mode(mode)
        .and_then(|m| m.run())
        .unwrap_or_else(|| panic!("{mode} did not run: {:?}", c.mode(mode)))
        .accuracy
        .position_rmse_m
}

#[test]
fn four_modes_with_the_paper_ordering_of_accuracy() {
    let c = full();
    eprintln!("{}", c.to_table());
    let names: Vec<&str> = c.modes.iter().map(|m| m.mode.as_str()).collect();
    let expected: Vec<&str> = Mode::ALL.iter().map(|m| m.name()).collect();
    assert_eq!(names, expected);
    assert_eq!(c.reference_poses, 601);
    for m in &c.modes {
        let run = m.run().unwrap_or_else(|| panic!("{} did not run", m.mode));
        assert!(
            run.accuracy.matched_poses >= 590,
            "{}: {:?}",
            m.mode,
            run.accuracy
        );
        assert!(run.stopped_early.is_none());
    }
    let (odo, com, las, both) = (
        rmse(c, "odometry"),
        rmse(c, "compass"),
        rmse(c, "laser"),
        rmse(c, "laser+compass"),
    );
    let table = c.to_table();
    // Dead reckoning with a 3 % wheel-scale error is by far the worst.
    assert!(odo > 0.5, "{table}");
    assert!(odo > com && odo > las && odo > both, "{table}");
    assert!(both < 0.05 * odo, "{table}");
    // With 1 cm ranges the lines fix the heading to a few hundredths of a degree, so a
    // 1° compass adds next to nothing; it also turns the first-scan map into its own
    // frame, which it knows only to about 1°/√600 ≈ 0.04° after the run: walls 5 m away
    // move by up to 3 mm. So laser+compass is within a millimetre of laser.
    assert!(
        both <= las + 0.001,
        "laser+compass {both:.6} m vs laser {las:.6} m\n{table}"
    );
    // The compass alone removes the heading drift of dead reckoning.
    let heading = |mode: &str| {
        c.mode(mode)
            .unwrap()
            .run()
            .unwrap()
            .accuracy
            .heading_rmse_deg
    };
    assert!(heading("compass") < 0.1 * heading("odometry"), "{table}");
    // What each mode fused.
    let run = |mode: &str| c.mode(mode).unwrap().run().unwrap();
    assert_eq!(
        (run("odometry").lines_fused, run("odometry").compass_fused),
        (0, 0)
    );
    assert!(run("compass").lines_fused == 0 && run("compass").compass_fused > 500);
    assert!(run("laser").lines_fused > 1000 && run("laser").compass_fused == 0);
    assert!(run("laser+compass").lines_fused > 1000 && run("laser+compass").compass_fused > 500);
    // The table names every mode and its numbers.
    for name in [
        "odometry",
        "compass",
        "laser",
        "laser+compass",
        "/ground_truth",
    ] {
        assert!(table.contains(name), "{table}");
    }
    assert!(table.contains(&format!("{odo:.3}")), "{table}");
}

#[test]
fn json_has_one_entry_per_mode_with_status() {
    let c = full();
    let v: serde_json::Value = serde_json::to_value(c).unwrap();
    let modes = v["modes"].as_array().unwrap();
    assert_eq!(modes.len(), 4);
    for (m, mode) in modes.iter().zip(Mode::ALL) {
        assert_eq!(m["mode"], mode.name());
        assert_eq!(m["status"], "ran");
        assert!(m["accuracy"]["position_rmse_m"].as_f64().unwrap() > 0.0);
        assert!(m["lines_fused"].is_u64() && m["compass_fused"].is_u64());
        // Trajectories and per-pose errors are for plots, not for the JSON.
        assert!(m.get("trajectory").is_none() && m.get("errors").is_none());
    }
    assert_eq!(v["reference_topic"], "/ground_truth");
    assert_eq!(v["reference_poses"], 601);
}

#[test]
fn one_svg_holds_fig_9_and_fig_10() {
    let c = full();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("compare.svg");
    write_svg(c, &path).unwrap();
    let svg = std::fs::read_to_string(&path).unwrap();
    let (polylines, texts) = inspect_svg(svg.as_bytes());
    // Fig. 9: the reference and four estimates; position error, x and y error: four each.
    assert_eq!(polylines, 5 + 3 * 4, "{texts:?}");
    for name in ["reference", "odometry", "compass", "laser", "laser+compass"] {
        assert!(
            texts.iter().any(|t| t == name),
            "no legend entry {name}: {texts:?}"
        );
    }
    // The reference is in the trajectory panel's legend only; each mode in all four.
    assert_eq!(texts.iter().filter(|t| *t == "reference").count(), 1);
    assert_eq!(texts.iter().filter(|t| *t == "laser+compass").count(), 4);
    for title in [
        "Fig. 9",
        "Deviation in X",
        "Deviation in Y",
        "Position error",
    ] {
        assert!(
            texts.iter().any(|t| t.contains(title)),
            "{title}: {texts:?}"
        );
    }
    // The same bytes as the writer form.
    let mut again = Vec::new();
    render_svg(c, &mut again).unwrap();
    assert_eq!(again, svg.as_bytes());
}

#[test]
fn a_log_without_reference_is_an_error_naming_the_topic() {
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("no_reference.mcap");
    write_room_bag(
        &log,
        BagContents {
            reference: false,
            ..BagContents::default()
        },
    );
    let err = compare(&log, &Config::default(), &CompareOptions::default()).unwrap_err();
    assert!(matches!(err, CompareError::NoReference { ref topic, .. } if topic == "/ground_truth"));
    let message = err.to_string();
    assert!(
        message.contains("reference") && message.contains("/ground_truth"),
        "{message}"
    );
    // It lists what the log has instead.
    assert!(
        message.contains("/scan") && message.contains("/joint_states"),
        "{message}"
    );

    // A configured reference topic is the one looked for.
    let mut config = Config::default();
    config.topics.ground_truth = "/mocap".into();
    let err = compare(&log, &config, &CompareOptions::default()).unwrap_err();
    assert!(err.to_string().contains("/mocap"), "{err}");
}

#[test]
fn a_mode_that_cannot_run_is_reported_and_the_others_still_run() {
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("no_compass.mcap");
    write_room_bag(
        &log,
        BagContents {
            compass: false,
            ..BagContents::default()
        },
    );
    let c = compare(&log, &Config::default(), &CompareOptions::default()).unwrap();
    assert_eq!(c.modes.len(), 4);
    for name in ["compass", "laser+compass"] {
        match &c.mode(name).unwrap().outcome {
            ModeOutcome::Unavailable { reason } => {
                assert!(reason.contains("/compass"), "{name}: {reason}")
            }
            other => panic!("{name} should not run without /compass: {other:?}"),
        }
    }
    assert!(rmse(&c, "laser") < 0.05 * rmse(&c, "odometry"));
    let table = c.to_table();
    assert_eq!(table.matches("not available").count(), 2, "{table}");
    let json = serde_json::to_value(&c).unwrap();
    assert_eq!(json["modes"][1]["status"], "unavailable");
    assert!(json["modes"][1]["reason"]
        .as_str()
        .unwrap()
        .contains("/compass"));

    // The SVG has the modes that ran, and none of the others.
    let mut svg = Vec::new();
    render_svg(&c, &mut svg).unwrap();
    let (polylines, texts) = inspect_svg(&svg);
    assert_eq!(polylines, 3 + 3 * 2);
    assert!(!texts.iter().any(|t| t == "compass" || t == "laser+compass"));
}

#[test]
fn a_missing_log_is_an_error() {
    let err = compare(
        Path::new("/nonexistent/log.mcap"),
        &Config::default(),
        &CompareOptions::default(),
    )
    .unwrap_err();
    assert!(matches!(err, CompareError::Read(_)), "{err:?}");
}
