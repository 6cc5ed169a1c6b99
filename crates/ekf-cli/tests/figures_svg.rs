//! The pictures of `ekf replay --svg` and `ekf evaluate --svg` parse as SVG, draw every
//! series as one line with a legend entry above the chart, the map's walls, and a marker
//! per event.

mod svg_support;

use ekf_cli::commands::figures::{evaluation_svg, replay_svg};
use ekf_cli::config::Config;
use ekf_cli::replay::{replay, ReplayEvent, ReplayOptions};
use std::path::{Path, PathBuf};
use svg_support::inspect_svg;

fn testdata(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../testdata")
        .join(name)
}

fn replayed() -> ekf_cli::replay::ReplayOutcome {
    let config = Config::preset("paper-robot").unwrap();
    let options = ReplayOptions {
        init_from_truth: true,
        keep_trajectories: true,
        ..ReplayOptions::default()
    };
    replay(
        &testdata("sim-paper.mcap"),
        &config,
        &options,
        &mut |_, _| {},
    )
    .unwrap()
}

/// `<circle>` elements of an SVG (the relocalization markers and the dots).
fn circles(svg: &[u8]) -> usize {
    let text = std::str::from_utf8(svg).unwrap();
    let doc = roxmltree::Document::parse(text).unwrap();
    doc.descendants()
        .filter(|n| n.has_tag_name("circle"))
        .count()
}

#[test]
fn a_replay_picture_shows_the_map_both_trajectories_the_errors_and_the_events() {
    let mut outcome = replayed();
    assert!(!outcome.map.is_empty() && !outcome.reference.is_empty());
    // Two relocalizations the replay did not have, at stamps of the run.
    let t = |k: usize| outcome.trajectory.samples[k].t_ns;
    outcome.events.retain(|e| e.1 != ReplayEvent::Relocalized);
    let before = {
        let mut svg = Vec::new();
        replay_svg(&outcome, Some(&outcome.map), "run", &mut svg).unwrap();
        circles(&svg)
    };
    let (t1, t2) = (t(100), t(400));
    outcome.events.push((t1, ReplayEvent::Relocalized));
    outcome.events.push((t2, ReplayEvent::Relocalized));
    outcome.events.sort_by_key(|e| e.0);
    let mut svg = Vec::new();
    replay_svg(
        &outcome,
        Some(&outcome.map),
        "sim-paper: laser+compass",
        &mut svg,
    )
    .unwrap();
    let (lines, texts) = inspect_svg(&svg);
    // Estimate and reference; the 2σ bound and the position error.
    assert_eq!(lines, 4, "{texts:?}");
    for name in [
        "sim-paper: laser+compass",
        "walls",
        "reference",
        "estimate",
        "2σ (filter)",
        "position error",
        "relocalized",
    ] {
        assert!(texts.iter().any(|t| t == name), "{name}: {texts:?}");
    }
    // The event legend is above both charts; two markers on each chart, plus one
    // circle in each legend.
    assert_eq!(texts.iter().filter(|t| *t == "relocalized").count(), 2);
    assert_eq!(circles(&svg) - before, 2 * 2 + 2);
}

#[test]
fn an_evaluation_picture_shows_both_trajectories_and_both_errors() {
    let outcome = replayed();
    let mut svg = Vec::new();
    evaluation_svg(
        &outcome.trajectory,
        &outcome.reference,
        true,
        "est against ref",
        &mut svg,
    )
    .unwrap();
    let (lines, texts) = inspect_svg(&svg);
    assert_eq!(lines, 4, "{texts:?}");
    for name in [
        "reference",
        "estimate (aligned)",
        "position error [m]",
        "heading error [deg]",
        "Position error (APE)",
        "Heading error",
    ] {
        assert!(texts.iter().any(|t| t == name), "{name}: {texts:?}");
    }
}
