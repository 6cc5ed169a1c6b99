//! `ekf corpus DIR`: the real-log benchmark. Every CARMEN log in a folder is imported as
//! it is, mapped from its reference, and replayed laser-only with the given (default)
//! configuration from the first reference pose; one row per log with the accuracy at
//! every scan and the wall time.

use super::import::{import_log, LogFormat};
use super::map::{build_map, MapSource};
use crate::config::Config;
use crate::import::CarmenOptions;
use crate::replay::{replay, Mode, ReplayOptions, ReplayOutcome};
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The initial pose of a `global` run `(x, y, θ)`: 1 km from the maps' origins, a
/// quarter turn off.
pub const GLOBAL_START: (f64, f64, f64) = (1000.0, 1000.0, std::f64::consts::FRAC_PI_2);

/// One log's result.
#[derive(Debug, Clone, Default, Serialize)]
pub struct CorpusRow {
    /// The log's name: its file name without `-corrected`, `.log` and `.gz`.
    pub log: String,
    /// Scans in the log.
    pub scans: u64,
    /// Timestamps the import repaired, and whether the clock was broken throughout.
    pub repaired_stamps: u64,
    /// The clock was broken throughout (synthetic times in file order).
    pub clock_broken: bool,
    /// Position RMSE against the reference at every scan (m).
    pub rmse_m: f64,
    /// Median position error (m).
    pub median_m: f64,
    /// 95th percentile of the position error (m).
    pub p95_m: f64,
    /// Largest position error (m).
    pub max_m: f64,
    /// Share of scans with an error over 0.5 m (0–1).
    pub over_half_m: f64,
    /// Share of scans with an error over 1 m (0–1).
    pub over_1m: f64,
    /// Losses: motion gaps and scans that began a run of unfused ones.
    pub losses: u64,
    /// Relocalizations that moved the filter.
    pub relocalizations: u64,
    /// Share of the reference poses (0–1) at which the filter said it was lost.
    pub lost: f64,
    /// Share of the other reference poses (the filter said it was tracking) with an
    /// error over 1 m (0–1): how often it is wrong without saying so.
    pub over_1m_tracked: f64,
    /// With `global`, the scan at which the search locked on (`None`: never).
    pub locked_on_scan: Option<u64>,
    /// Wall time of the replay alone (s).
    pub replay_s: f64,
    /// Wall time of import, map and replay (s).
    pub wall_time_s: f64,
    /// Why the log could not be run, if it could not (the other fields are then 0).
    pub error: Option<String>,
}

/// The logs `paths` name: a file as it is, a folder as its CARMEN logs
/// ([`corpus_logs`]). An error names the folder that could not be read.
pub fn logs_of(paths: &[PathBuf]) -> std::io::Result<Vec<PathBuf>> {
    let mut logs = Vec::new();
    for path in paths {
        if path.is_dir() {
            let found = corpus_logs(path)
                .map_err(|e| std::io::Error::new(e.kind(), format!("{}: {e}", path.display())))?;
            logs.extend(found);
        } else {
            logs.push(path.clone());
        }
    }
    Ok(logs)
}

/// The CARMEN logs in `dir` (`*.log`, `*.log.gz`), sorted by name.
pub fn corpus_logs(dir: &Path) -> std::io::Result<Vec<PathBuf>> {
    let mut logs: Vec<PathBuf> = std::fs::read_dir(dir)?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            let name = p.file_name().and_then(|n| n.to_str()).unwrap_or("");
            name.ends_with(".log") || name.ends_with(".log.gz")
        })
        .collect();
    logs.sort();
    Ok(logs)
}

/// A log's short name: `seattle-corrected.log.gz` → `seattle`.
pub fn log_name(path: &Path) -> String {
    let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("log");
    let name = name.strip_suffix(".gz").unwrap_or(name);
    let name = name.strip_suffix(".log").unwrap_or(name);
    name.strip_suffix("-corrected").unwrap_or(name).to_string()
}

/// Imports, maps and replays one log, with intermediate files in `work_dir`; with
/// `global`, without an initial pose (`ekf replay --global`, starting at
/// [`GLOBAL_START`], whose error counts until the search locks on).
pub fn run_log(log: &Path, config: &Config, work_dir: &Path, global: bool) -> CorpusRow {
    let started = Instant::now();
    let name = log_name(log);
    let mut row = CorpusRow {
        log: name.clone(),
        ..CorpusRow::default()
    };
    if let Err(e) = fill_row(log, config, work_dir, &name, global, &mut row) {
        row.error = Some(e);
    }
    row.wall_time_s = started.elapsed().as_secs_f64();
    row
}

fn fill_row(
    log: &Path,
    config: &Config,
    work_dir: &Path,
    name: &str,
    global: bool,
    row: &mut CorpusRow,
) -> Result<(), String> {
    let bag = work_dir.join(format!("{name}.mcap"));
    let imported = import_log(log, &bag, LogFormat::Carmen(CarmenOptions::default()))
        .map_err(|e| e.to_string())?;
    row.scans = imported.stats.scans;
    row.repaired_stamps = imported.stats.time_repairs.repaired();
    row.clock_broken = imported.stats.time_repairs.clock_broken;
    let (map, _) = build_map(&bag, config, MapSource::Reference(Default::default()))
        .map_err(|e| e.to_string())?;
    let map_path = work_dir.join(format!("{name}-map.json"));
    let json = map.to_json().map_err(|e| e.to_string())?;
    std::fs::write(&map_path, json).map_err(|e| format!("{}: {e}", map_path.display()))?;
    let options = ReplayOptions {
        mode: Mode::Laser,
        map: Some(map_path),
        init_from_truth: !global,
        out_mcap: None,
        tum: Some(work_dir.join(format!("{name}.tum"))),
        keep_trajectories: true,
        global,
        grow_map: false,
    };
    let mut config = config.clone();
    if global {
        // Far outside every map and turned: a pose is only ever right once the search has
        // found it, never because the log starts where the default initial pose is.
        (config.initial.x, config.initial.y, config.initial.theta) = GLOBAL_START;
    }
    let outcome = replay(&bag, &config, &options, &mut |_, _| {}).map_err(|e| e.to_string())?;
    if let Some(failure) = outcome.failure {
        return Err(failure.to_string());
    }
    (row.lost, row.over_1m_tracked) = lost_and_wrong(&outcome);
    let s = outcome.summary;
    let a = s
        .accuracy
        .ok_or_else(|| "no pose matched a reference pose".to_string())?;
    row.rmse_m = a.position_rmse_m;
    row.median_m = a.position_median_m;
    row.p95_m = a.position_p95_m;
    row.max_m = a.position_max_m;
    row.over_half_m = a.share_over_half_m;
    row.over_1m = a.share_over_1m;
    row.losses = s.tracking.losses;
    row.relocalizations = s.tracking.relocalizations;
    row.locked_on_scan = s.tracking.locked_on_scan;
    row.replay_s = s.wall_time_s;
    Ok(())
}

/// At the reference poses: the share at which the filter said it was lost, and the share
/// of the others with a position error over 1 m. Each reference pose is compared with the
/// latest estimate at or before it; references before the first estimate are skipped.
pub fn lost_and_wrong(outcome: &ReplayOutcome) -> (f64, f64) {
    let estimates = &outcome.trajectory.samples;
    let lost = &outcome.lost_scans_ns;
    let (mut lost_count, mut tracked, mut wrong) = (0usize, 0usize, 0usize);
    for r in &outcome.reference.samples {
        let Some(e) = estimates
            .partition_point(|e| e.t_ns <= r.t_ns)
            .checked_sub(1)
            .and_then(|i| estimates.get(i))
        else {
            continue;
        };
        if lost.binary_search(&e.t_ns).is_ok() {
            lost_count += 1;
        } else {
            tracked += 1;
            let error = (e.pose.x - r.pose.x).hypot(e.pose.y - r.pose.y);
            wrong += usize::from(error > 1.0);
        }
    }
    let share = |n: usize, of: usize| if of == 0 { 0.0 } else { n as f64 / of as f64 };
    (
        share(lost_count, lost_count + tracked),
        share(wrong, tracked),
    )
}

/// The rows as a Markdown table (with the lock-on scan when `global`).
pub fn table(rows: &[CorpusRow], global: bool) -> String {
    let mut t = format!(
        "| log | scans | RMSE (m) | median | p95 | max | > 0.5 m | > 1 m | losses | \
         relocalizations | lost | > 1 m tracked | replay (s) |{}\n\
         |---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|{}\n",
        if global { " locked on at scan |" } else { "" },
        if global { "---:|" } else { "" },
    );
    for r in rows {
        if let Some(e) = &r.error {
            t.push_str(&format!(
                "| {} | – | failed: {e} | | | | | | | | | | |\n",
                r.log
            ));
            continue;
        }
        t.push_str(&format!(
            "| {} | {} | {:.3} | {:.3} | {:.3} | {:.2} | {:.1} % | {:.1} % | {} | {} | {:.1} % | {:.1} % | {:.2} |",
            r.log,
            r.scans,
            r.rmse_m,
            r.median_m,
            r.p95_m,
            r.max_m,
            100.0 * r.over_half_m,
            100.0 * r.over_1m,
            r.losses,
            r.relocalizations,
            100.0 * r.lost,
            100.0 * r.over_1m_tracked,
            r.replay_s
        ));
        if global {
            let lock = r
                .locked_on_scan
                .map_or("never".to_string(), |k| k.to_string());
            t.push_str(&format!(" {lock} |"));
        }
        t.push('\n');
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_folder_stands_for_its_carmen_logs_in_name_order_and_a_file_for_itself() {
        let dir = tempfile::tempdir().unwrap();
        for name in ["b-corrected.log.gz", "a.log", "notes.txt"] {
            std::fs::write(dir.path().join(name), "").unwrap();
        }
        let single = PathBuf::from("elsewhere/x.log.gz");
        let logs = logs_of(&[dir.path().to_path_buf(), single.clone()]).unwrap();
        assert_eq!(
            logs,
            [
                dir.path().join("a.log"),
                dir.path().join("b-corrected.log.gz"),
                single
            ]
        );
        assert_eq!(log_name(&logs[1]), "b");
        let missing = dir.path().join("gone");
        std::fs::create_dir(&missing).unwrap();
        std::fs::remove_dir(&missing).unwrap();
        // A path that is not a folder is taken as a log (its import will name it).
        assert_eq!(logs_of(std::slice::from_ref(&missing)).unwrap(), [missing]);
    }
}
