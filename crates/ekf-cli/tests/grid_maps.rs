//! Occupancy-grid maps in and out on the bundled ACES log: the line map drawn as a Nav2
//! grid and read back, and a grid made from the scans as a SLAM mapper would, each
//! localize ACES about as well as the line map built from the reference.

mod grid_support;

use ekf_cli::commands::grid::{self, GridImportParams};
use ekf_cli::config::Config;
use ekf_cli::replay::{replay, Mode, ReplayOptions};
use lrf_lines::LineMap;
use std::path::{Path, PathBuf};

fn testdata(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../testdata")
        .join(name)
}

/// Position RMSE of ACES replayed laser-only from its first reference pose against
/// `map`, and the losses on the way (tracking again at the end).
fn rmse_with(map: &Path) -> (f64, u64) {
    let options = ReplayOptions {
        mode: Mode::Laser,
        map: Some(map.to_path_buf()),
        init_from_truth: true,
        out_mcap: None,
        tum: None,
        keep_trajectories: false,
        global: false,
        grow_map: false,
    };
    let outcome = replay(
        &testdata("aces.mcap"),
        &Config::default(),
        &options,
        &mut |_, _| {},
    )
    .unwrap();
    assert!(outcome.failure.is_none(), "{:?}", outcome.failure);
    let s = outcome.summary;
    assert_eq!(s.tracking.lost_at_end, 0, "{:?}", s.tracking);
    (s.accuracy.unwrap().position_rmse_m, s.tracking.losses)
}

/// The walls of the grid `yaml`, written as a line map beside it.
fn import(yaml: &Path) -> (PathBuf, grid::GridImportSummary) {
    let config = Config::default();
    let (map, summary) = grid::import(
        yaml,
        &config.localizer.extraction,
        &GridImportParams::default(),
    )
    .unwrap();
    let out = yaml.with_extension("json");
    std::fs::write(&out, map.to_json().unwrap()).unwrap();
    (out, summary)
}

#[test]
fn the_aces_map_drawn_as_a_grid_and_read_back_localizes_within_2_cm_of_it() {
    let dir = tempfile::tempdir().unwrap();
    let map_path = testdata("aces-map.json");
    let line_map = LineMap::from_json(&std::fs::read_to_string(&map_path).unwrap()).unwrap();
    let yaml = dir.path().join("aces-grid.yaml");
    let exported = grid::export(&line_map, &map_path, &yaml, 0.05, 1.0).unwrap();
    assert_eq!(exported.image, dir.path().join("aces-grid.pgm"));
    assert_eq!(exported.segments, line_map.len());
    let (back, summary) = import(&yaml);
    assert_eq!(summary.unknown_cells, 0, "{summary:?}");
    let ((json, json_losses), (grid, grid_losses)) = (rmse_with(&map_path), rmse_with(&back));
    assert_eq!((json_losses, grid_losses), (0, 0));
    assert!(
        grid - json <= 0.02,
        "RMSE {grid:.4} m with the grid's walls, {json:.4} m with the line map"
    );
}

/// The maps issue asks for 0.03 m here. With the import's defaults this grid gives
/// 0.1020 m against 0.0724 m with the line map (0.0296 apart); other lattice spacings
/// and sighting counts give 0.095–0.24 m (docs/maps.md): the tracking is sensitive to
/// small differences in the walls, so a change elsewhere can move this by more than the
/// margin. Deterministic on one machine: same log, same code, same number.
#[test]
fn a_grid_mapped_from_the_aces_scans_localizes_within_3_cm_of_the_line_map() {
    let dir = tempfile::tempdir().unwrap();
    let yaml =
        grid_support::gmapping_style_grid(&testdata("aces.mcap"), 0.05, dir.path(), "aces-slam");
    let (walls, summary) = import(&yaml);
    assert!(
        summary.unknown_cells > 0 && summary.occupied_cells > 0,
        "{summary:?}"
    );
    let ((json, json_losses), (grid, grid_losses)) =
        (rmse_with(&testdata("aces-map.json")), rmse_with(&walls));
    // One loss, regained by tracking: 3 scans in a row fused no line while a check of
    // an uncertain heading had been refused (14 scans unconfirmed in all).
    assert_eq!((json_losses, grid_losses), (0, 1));
    assert!(
        grid - json <= 0.03,
        "RMSE {grid:.4} m with the grid's walls, {json:.4} m with the line map"
    );
}
