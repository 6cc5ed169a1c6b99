//! `ekf`: localization from wheel odometry, a compass and laser lines. See `ekf --help`.
//!
//! This file only parses arguments, calls the library and prints what it returns.

use clap::ValueEnum;
use clap::{Parser, Subcommand};
use ekf_cli::commands::{
    self, compare, corpus, emulate, evaluate, experiment, figures, import, map, simulate,
};
use ekf_cli::config::{Config, DEFAULT_TOML};
use ekf_cli::emulate::Device;
use ekf_cli::import::{CarmenFlavour, CarmenOptions, RangeMaxSource, SyntheticCompass};
use ekf_cli::live;
use ekf_cli::replay::{self, Mode, ReplayOptions};
use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;

/// EKF localization with wheel odometry, a compass and 2-D laser line features.
#[derive(Debug, Parser)]
#[command(name = "ekf", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Run the filter over a ROS 2 bag (MCAP or sqlite3): a trajectory (TUM), an MCAP for Foxglove
    /// and ROS 2 tools, and a summary (with accuracy when the log has a reference).
    Replay {
        /// The ROS 2 bag: an .mcap or .db3 file, or a bag directory as `ros2 bag record`
        /// writes it.
        log: PathBuf,
        /// Configuration file (TOML); `ekf config` prints the defaults.
        #[arg(long)]
        config: Option<PathBuf>,
        /// Line map (JSON). Without it the map is built from the first scan, as in the paper.
        #[arg(long)]
        map: Option<PathBuf>,
        /// Which sensors the filter uses (the paper's four configurations).
        #[arg(long, value_enum, default_value_t = CliMode::LaserCompass)]
        mode: CliMode,
        /// Start at the log's first reference pose instead of the configured initial pose.
        #[arg(long)]
        init_from_truth: bool,
        /// Global localization: no initial pose; search the map (--map) from the first
        /// scans and start where the search locks on (the summary says at which scan).
        #[arg(long, conflicts_with = "init_from_truth", requires = "map")]
        global: bool,
        /// Write the estimate, lines, map and diagnostics to this MCAP bag (a path ending
        /// in `/`: a bag directory with metadata.yaml, as `ros2 bag record` writes).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Write the trajectory as TUM text (what evo reads).
        #[arg(long)]
        tum: Option<PathBuf>,
        /// Draw the trajectory over the map with the reference, the error over time and
        /// markers where lines were refused, the compass rejected, the filter lost or
        /// relocalized, as one SVG.
        #[arg(long)]
        svg: Option<PathBuf>,
        /// Print the summary as one JSON object.
        #[arg(long)]
        json: bool,
    },
    /// The paper's Fig. 9/10: replay a bag in all four modes (odometry, compass, laser,
    /// laser+compass) and compare each estimate with the log's reference trajectory.
    Compare {
        /// The ROS 2 bag (.mcap, .db3 or a bag directory); it needs a reference trajectory (topics.ground_truth).
        log: PathBuf,
        /// Configuration file (TOML); `ekf config` prints the defaults.
        #[arg(long)]
        config: Option<PathBuf>,
        /// Line map (JSON). Without it the map is built from the first scan, as in the paper.
        #[arg(long)]
        map: Option<PathBuf>,
        /// Start at the log's first reference pose instead of the configured initial pose.
        #[arg(long)]
        init_from_truth: bool,
        /// Write one SVG with the trajectories (Fig. 9) and the position, x and y errors
        /// over time (Fig. 10).
        #[arg(long)]
        svg: Option<PathBuf>,
        /// Print one JSON object instead of a table.
        #[arg(long)]
        json: bool,
    },
    /// The paper's experiments in simulation: an SVG figure and a JSON table each.
    Experiment {
        /// fig9 (Fig. 9/10 over seeds, with NEES), fig11 (path following with and
        /// without the EKF), fig12 (driving round the first-scan map's walls).
        #[arg(value_enum)]
        figure: Figure,
        /// Where the figure, the table and logs go.
        #[arg(long, default_value = "out/experiments")]
        out_dir: PathBuf,
        /// The first seed.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Seeds to run (fig9; the figures show the first).
        #[arg(long, default_value_t = 20)]
        seeds: u32,
        /// Simulated time per run (s); default: the scenario's (120 s).
        #[arg(long)]
        duration: Option<f64>,
        /// Print the table as JSON (it is also written to OUT_DIR).
        #[arg(long)]
        json: bool,
    },
    /// Print the documented default configuration (TOML), or a preset's overrides.
    Config {
        /// A built-in preset instead of the defaults (paper-robot: the simulated robot).
        #[arg(long)]
        preset: Option<String>,
    },
    /// Simulate the paper's robot in a room and write a ROS 2 bag with exact ground truth
    /// (/joint_states, /compass, /scan, /tf_static, /ground_truth).
    Simulate {
        /// A built-in scenario (paper, triangle, walls, l-room, corridor) or a line map
        /// (.json) whose room the robot drives around 1 m inside.
        scenario: String,
        /// The bag to write: an MCAP file, or with a path ending in `/` a bag directory
        /// with metadata.yaml.
        #[arg(long)]
        out: PathBuf,
        /// Noise seed: the same seed gives the same bytes.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Simulated time (s); default: the scenario's (120 s).
        #[arg(long)]
        duration: Option<f64>,
        /// What steers the robot along its path.
        #[arg(long, value_enum, default_value_t = CliSteering::Truth)]
        steer_by: CliSteering,
        /// Laser angular resolution (degrees): 0.25, 0.5 or 1.
        #[arg(long)]
        resolution: Option<f64>,
        /// Wheel slip events per minute (default: none).
        #[arg(long)]
        slips_per_minute: Option<f64>,
        /// Compass bias (degrees; default 0).
        #[arg(long, allow_hyphen_values = true)]
        compass_bias: Option<f64>,
        /// Probability of a compass outlier per reading (default 0.02).
        #[arg(long)]
        compass_outliers: Option<f64>,
        /// Print the summary as JSON.
        #[arg(long)]
        json: bool,
    },
    /// Run the filter on the robot's serial devices (SICK LMS 2xx, MODBUS base
    /// controller, NMEA GPS), print poses, and record everything for `ekf replay`.
    Live {
        /// The laser's serial port.
        #[arg(long)]
        laser: String,
        /// The base controller's serial port (RS-485, MODBUS RTU).
        #[arg(long)]
        base: String,
        /// The GPS's serial port (NMEA).
        #[arg(long)]
        gps: Option<String>,
        /// Configuration file (TOML); `ekf config` prints the defaults.
        #[arg(long)]
        config: Option<PathBuf>,
        /// Line map (JSON). Without it the map is built from the first scan, as in the paper.
        #[arg(long)]
        map: Option<PathBuf>,
        /// Which sensors the filter uses.
        #[arg(long, value_enum, default_value_t = CliMode::LaserCompass)]
        mode: CliMode,
        /// Record the raw readings, /tf_static and the estimates to this MCAP bag (a path
        /// ending in `/`: a bag directory with metadata.yaml).
        #[arg(long)]
        record: Option<PathBuf>,
        /// Print poses and the summary as JSON lines.
        #[arg(long)]
        json: bool,
    },
    /// Emulate the robot's devices on pseudo-terminals, driven in real time by the
    /// simulator, for `ekf live` to run against; prints the device paths.
    Emulate {
        /// A built-in scenario (paper, triangle, walls, l-room, corridor) or a line map
        /// (.json) whose room the robot drives around 1 m inside.
        #[arg(long, default_value = "paper")]
        scenario: String,
        /// Noise seed.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// How long the robot drives (s), from when ekf live has connected; default: the
        /// scenario's (120 s).
        #[arg(long)]
        duration: Option<f64>,
        /// Write the true pose (/ground_truth, nav_msgs/Odometry) to this MCAP, stamped
        /// with the wall clock as ekf live stamps its recording.
        #[arg(long)]
        truth: Option<PathBuf>,
        /// Folder for the device links (laser, base, gps) and live.toml (which stays, for
        /// ekf replay of a recording); default: a new one in the temporary folder,
        /// removed at the end.
        #[arg(long)]
        dir: Option<PathBuf>,
        /// Where the room's origin lies (`LAT,LON[,ALT]`; x east, y north): the GPS reports
        /// fixes of the robot. Default: no fix, as indoors.
        #[arg(long, allow_hyphen_values = true)]
        gps_origin: Option<ekf_cli::geo::GeoOrigin>,
        /// Print the summary as JSON.
        #[arg(long)]
        json: bool,
    },
    /// Line maps.
    Map {
        #[command(subcommand)]
        action: MapAction,
    },
    /// Convert a CARMEN or MRPT text log into a ROS 2 bag (MCAP) with /odom, /scan,
    /// /tf_static, /ground_truth (corrected CARMEN logs) and optionally a synthetic /compass.
    Import {
        #[command(subcommand)]
        format: ImportFormat,
    },
    /// The real-log benchmark: import each CARMEN log (a file, or every *.log / *.log.gz
    /// in a folder), build its map from the reference, replay it laser-only from the first
    /// reference pose, and print one row per log.
    Corpus {
        /// CARMEN logs, or folders of them.
        #[arg(required = true)]
        paths: Vec<PathBuf>,
        /// Where the imported bags, maps and TUM trajectories go.
        #[arg(long, default_value = "out/corpus")]
        work_dir: PathBuf,
        /// Filter settings (TOML); default: the documented defaults.
        #[arg(long)]
        config: Option<PathBuf>,
        /// Global localization: replay without an initial pose (ekf replay --global).
        #[arg(long)]
        global: bool,
        /// Print the rows as JSON instead of a table.
        #[arg(long)]
        json: bool,
    },
    /// Absolute and relative pose errors of a trajectory against a reference, as `evo`
    /// computes them (same frame, no alignment unless --align).
    Evaluate {
        /// The estimated trajectory: a TUM file, or a ROS 2 bag (its /ekf/pose, else
        /// /ground_truth, unless --est-topic names one).
        estimate: PathBuf,
        /// The reference trajectory: a TUM file, or a ROS 2 bag (its /ground_truth unless
        /// --truth-topic names one).
        #[arg(long)]
        truth: PathBuf,
        /// Pose topic of a bag estimate.
        #[arg(long)]
        est_topic: Option<String>,
        /// Pose topic of a bag reference.
        #[arg(long, default_value = "/ground_truth")]
        truth_topic: String,
        /// Align the estimate to the reference first (rigid SE(2) Umeyama, as `evo -a`).
        #[arg(long)]
        align: bool,
        /// Draw both trajectories and the position and heading errors over time as one
        /// SVG (as `evo_ape --plot`).
        #[arg(long)]
        svg: Option<PathBuf>,
        /// Print one JSON object instead of a table.
        #[arg(long)]
        json: bool,
    },
}

#[derive(Debug, Subcommand)]
enum ImportFormat {
    /// A CARMEN log (ODOM, FLASER, ROBOTLASER1), plain or "corrected"; .gz is read directly.
    Carmen {
        /// The CARMEN log.
        input: PathBuf,
        /// The bag to write: an MCAP file, or with a path ending in `/` a bag directory
        /// with metadata.yaml.
        #[arg(long)]
        out: PathBuf,
        /// Which flavour the log is: corrected (SLAM poses at the scans, odometry reset
        /// to them), plain, or auto (corrected if the resets are found).
        #[arg(long, value_enum, default_value_t = Flavour::Auto)]
        flavour: Flavour,
        /// Range limit of FLASER scans (m) unless the log's PARAM lines give one.
        #[arg(long, default_value_t = 50.0)]
        laser_max_range: f64,
        /// Also write a SYNTHETIC /compass: the reference heading plus Gaussian noise of
        /// this standard deviation (degrees). Labelled as synthetic in the bag's metadata.
        #[arg(long, value_name = "SIGMA")]
        synthetic_compass_deg: Option<f64>,
        /// Seed of the synthetic compass noise.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Refuse a log whose timestamps need repair (negative, zero, below a nanosecond,
        /// out of order, or a clock broken throughout) instead of repairing them.
        #[arg(long)]
        strict: bool,
        /// Print the summary as JSON.
        #[arg(long)]
        json: bool,
    },
    /// MRPT's text export (ODOM, RAWSCAN).
    Mrpt {
        /// The MRPT text log.
        input: PathBuf,
        /// The bag to write: an MCAP file, or with a path ending in `/` a bag directory
        /// with metadata.yaml.
        #[arg(long)]
        out: PathBuf,
        /// Print the summary as JSON.
        #[arg(long)]
        json: bool,
    },
}

#[derive(Debug, Subcommand)]
enum MapAction {
    /// Build a line map (JSON) from a bag: from its first scan (the paper's global map),
    /// or with --from-truth from every scan placed along the log's reference trajectory.
    Build {
        /// The ROS 2 bag: an .mcap or .db3 file, or a bag directory as `ros2 bag record`
        /// writes it.
        log: PathBuf,
        /// The map file to write.
        #[arg(long)]
        out: PathBuf,
        /// Place every scan at the reference pose and fuse repeated sightings of a wall.
        #[arg(long)]
        from_truth: bool,
        /// With a first-scan map: place the scan at the first reference pose instead of
        /// the configured initial pose.
        #[arg(long)]
        init_from_truth: bool,
        /// Configuration file (TOML): topics, laser mount, extraction parameters.
        #[arg(long)]
        config: Option<PathBuf>,
        /// Print the summary as JSON.
        #[arg(long)]
        json: bool,
    },
}

#[derive(Debug, Clone, Copy, ValueEnum)]
enum Figure {
    Fig9,
    Fig11,
    Fig12,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
enum CliSteering {
    /// The true pose.
    Truth,
    /// The laser + compass EKF in the loop.
    Ekf,
    /// Dead reckoning.
    Odometry,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
enum CliMode {
    Odometry,
    Compass,
    Laser,
    #[value(name = "laser+compass")]
    LaserCompass,
}

impl From<CliMode> for Mode {
    fn from(m: CliMode) -> Self {
        match m {
            CliMode::Odometry => Mode::Odometry,
            CliMode::Compass => Mode::Compass,
            CliMode::Laser => Mode::Laser,
            CliMode::LaserCompass => Mode::LaserCompass,
        }
    }
}

/// The file name of `path`, for figure titles.
fn file_name(path: &std::path::Path) -> String {
    path.file_name()
        .unwrap_or(path.as_os_str())
        .to_string_lossy()
        .into_owned()
}

/// Creates the folder an output file goes into, so `--out results/run.mcap` just works.
fn create_parent(path: &std::path::Path) -> Result<(), String> {
    match path.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => {
            ekf_cli::commands::create_output_dir(dir).map_err(|e| format!("{}: {e}", dir.display()))
        }
        _ => Ok(()),
    }
}

fn load_config(path: Option<&std::path::Path>) -> Result<Config, Box<dyn std::error::Error>> {
    Ok(match path {
        Some(p) => Config::load(p)?,
        None => Config::default(),
    })
}

/// A progress bar on stderr when it is a terminal; nothing otherwise.
fn progress_bar() -> Option<indicatif::ProgressBar> {
    std::io::stderr().is_terminal().then(|| {
        let bar = indicatif::ProgressBar::new(0);
        bar.set_style(
            indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} messages {eta}")
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        bar
    })
}

fn print_replay_table(s: &replay::ReplaySummary) {
    println!(
        "{} ({}, map: {}, {} segments)",
        s.log, s.mode, s.map, s.map_segments
    );
    println!(
        "  motion steps {}, poses written {}, scans {} (used {})",
        s.motion_steps, s.poses_written, s.lines.scans, s.lines.scans_used
    );
    println!(
        "  lines: extracted {}, matched {}, rejected {}, fused {}, refused {}",
        s.lines.extracted, s.lines.matched, s.lines.rejected, s.lines.fused, s.lines.refused
    );
    println!(
        "  compass: fused {} ({} to end a gate lock-out), rejected {}",
        s.compass.accepted, s.compass.recovered, s.compass.rejected
    );
    if s.gps.accepted + s.gps.rejected > 0 {
        println!(
            "  gps: fused {}, rejected {}",
            s.gps.accepted, s.gps.rejected
        );
    }
    if let Some(a) = &s.accuracy {
        println!("  accuracy vs reference ({} poses): position RMSE {:.3} m (median {:.3}, p95 {:.3}, max {:.3} m; over 1 m on {:.1} %), heading RMSE {:.2}°", a.matched_poses, a.position_rmse_m, a.position_median_m, a.position_p95_m, a.position_max_m, 100.0 * a.share_over_1m, a.heading_rmse_deg);
    }
    let t = &s.timings;
    println!("  per scan (median/p99 µs): extraction {:.1}/{:.1}, matching {:.1}/{:.1}, update {:.1}/{:.1}", t.extraction.median_us, t.extraction.p99_us, t.matching.median_us, t.matching.p99_us, t.update.median_us, t.update.p99_us);
    if s.warning_count > 0 {
        println!(
            "  {} messages skipped, e.g. {} at {} ns: {}",
            s.warning_count, s.warnings[0].topic, s.warnings[0].log_time_ns, s.warnings[0].reason
        );
    }
    let k = &s.tracking;
    if k.losses + k.searches > 0 || k.locked_on_scan.is_some() {
        let lock = k
            .locked_on_scan
            .map_or(String::new(), |n| format!("; locked on at scan {n}"));
        println!(
            "  tracking: lost {} times ({} motion gaps), {} scans lost, {} relocalizations ({} searches, {} refused){lock}{}",
            k.losses,
            k.motion_gaps,
            k.scans_lost,
            k.relocalizations,
            k.searches,
            k.refused,
            if k.lost_at_end > 0 { "; lost at the end" } else { "" }
        );
    }
    let c = &s.consistency;
    if let Some(nis) = c.nis_per_dof {
        println!(
            "  line innovations: NIS per dof {nis:.2}; over-confident on {} of {} scans ({} stretches)",
            c.over_confident_scans, c.scans, c.over_confident_stretches
        );
    }
    for note in &s.notes {
        println!("  note: {note}");
    }
    println!("  wall time {:.2} s", s.wall_time_s);
}

#[derive(Debug, Clone, Copy, ValueEnum)]
enum Flavour {
    Auto,
    Corrected,
    Plain,
}

fn print_import(
    summary: &import::ImportSummary,
    out: &std::path::Path,
    json: bool,
) -> Result<(), Box<dyn std::error::Error>> {
    if json {
        println!("{}", serde_json::to_string_pretty(summary)?);
    } else {
        let s = &summary.stats;
        println!(
            "{}: {} messages ({} odometry, {} scans, {} reference, {} compass) over {:.1} s",
            out.display(),
            summary.messages_written,
            s.odometry,
            s.scans,
            s.references,
            s.compass,
            s.span_ns() as f64 * 1e-9
        );
        if let Some(r) = s.laser_range_max {
            let source = match r.source {
                RangeMaxSource::Saturation => "where the readings saturate",
                RangeMaxSource::Param => "the log's PARAM robot_front_laser_max",
                RangeMaxSource::Default => "--laser-max-range",
            };
            println!(
                "  laser readings from {:.2} m up are no return ({source})",
                r.value
            );
        }
        for line in import::repair_lines(s) {
            eprintln!("warning: {line}");
        }
    }
    Ok(())
}

fn print_live_event(event: &live::LiveEvent, json: bool) {
    match event {
        live::LiveEvent::Pose {
            t_ns,
            fused_ns,
            pose,
            covariance,
        } => {
            if json {
                let line = serde_json::json!({
                    "t_ns": t_ns, "fused_ns": fused_ns,
                    "x": pose.x, "y": pose.y, "theta": pose.theta,
                    "sigma_xy": [covariance[(0, 0)].sqrt(), covariance[(1, 1)].sqrt()],
                    "sigma_theta": covariance[(2, 2)].sqrt(),
                });
                println!("{line}");
            } else {
                println!(
                    "{:.3}  x {:8.3} m  y {:8.3} m  θ {:7.2}°  σxy {:.3} m  (odometry since {:.2} s)",
                    *t_ns as f64 * 1e-9,
                    pose.x,
                    pose.y,
                    pose.theta.to_degrees(),
                    (covariance[(0, 0)] + covariance[(1, 1)]).sqrt(),
                    t_ns.saturating_sub(*fused_ns) as f64 * 1e-9
                );
            }
        }
        live::LiveEvent::Device { level, text, .. } => {
            let what = if *level == 0 { "" } else { "warning: " };
            eprintln!("ekf: {what}{text}");
        }
    }
}

fn print_live_summary(s: &live::LiveSummary) {
    let f = &s.filter;
    println!(
        "live: motion steps {}, scans {} (used {}), lines fused {}, compass fused {}",
        f.motion_steps, f.lines.scans, f.lines.scans_used, f.lines.fused, f.compass.accepted
    );
    for (device, counters) in &s.devices {
        println!("  {device}: {counters}");
    }
    for (device, n) in &s.reconnects {
        println!("  {device}: reconnected {n} times");
    }
    if let Some(r) = &s.recording {
        println!("  recording: {r}");
    }
}

fn run(cli: Cli) -> Result<(), Box<dyn std::error::Error>> {
    match cli.command {
        Command::Experiment {
            figure,
            out_dir,
            seed,
            seeds,
            duration,
            json,
        } => {
            let options = experiment::ExperimentOptions {
                out_dir,
                seed,
                seeds,
                duration_s: duration,
            };
            let (json_text, text) = match figure {
                Figure::Fig9 => {
                    let r = experiment::fig9::run(&options)?;
                    (serde_json::to_string_pretty(&r)?, r.to_text())
                }
                Figure::Fig11 => {
                    let r = experiment::fig11::run(&options)?;
                    (serde_json::to_string_pretty(&r)?, r.to_text())
                }
                Figure::Fig12 => {
                    let r = experiment::fig12::run(&options)?;
                    (serde_json::to_string_pretty(&r)?, r.to_text())
                }
            };
            if json {
                println!("{json_text}");
            } else {
                print!("{text}");
            }
        }
        Command::Config { preset: None } => print!("{DEFAULT_TOML}"),
        Command::Config { preset: Some(name) } => print!("{}", Config::preset_text(&name)?),
        Command::Simulate {
            scenario,
            out,
            seed,
            duration,
            steer_by,
            resolution,
            slips_per_minute,
            compass_bias,
            compass_outliers,
            json,
        } => {
            let options = simulate::SimulateOptions {
                seed,
                duration_s: duration,
                steering: match steer_by {
                    CliSteering::Truth => simulate::Steering::Truth,
                    CliSteering::Ekf => simulate::Steering::Ekf,
                    CliSteering::Odometry => simulate::Steering::Odometry,
                },
                resolution_deg: resolution,
                slips_per_minute,
                compass_bias_deg: compass_bias,
                compass_outliers,
            };
            let scenario = simulate::load_scenario(&scenario, &options)?;
            create_parent(&out)?;
            let (_, summary) = simulate::run_simulation(&scenario, &options, Some(&out))?;
            if json {
                println!("{}", serde_json::to_string_pretty(&summary)?);
            } else {
                let s = &summary.stats;
                println!(
                    "{}: {} ({} s, seed {}): {} messages, {} scans, {:.1} m driven, {} compass outliers, {} slips, closest to a wall {:.2} m",
                    summary.out, summary.scenario, summary.duration_s, summary.seed,
                    summary.messages, s.scans, s.distance_m, s.compass_outliers, s.slips,
                    s.min_clearance_m
                );
            }
        }
        Command::Live {
            laser,
            base,
            gps,
            config,
            map,
            mode,
            record,
            json,
        } => {
            let config = load_config(config.as_deref())?;
            if let Some(path) = &record {
                create_parent(path)?;
            }
            let options = live::LiveOptions {
                laser,
                base,
                gps,
                record,
                map,
                mode: mode.into(),
            };
            let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
            for signal in [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM] {
                signal_hook::flag::register(signal, std::sync::Arc::clone(&stop))?;
            }
            let outcome = live::run(&config, &options, stop, &mut |event| {
                print_live_event(&event, json)
            })?;
            if json {
                println!("{}", serde_json::to_string(&outcome.summary)?);
            } else {
                print_live_summary(&outcome.summary);
            }
            if let Some(failure) = outcome.failure {
                return Err(failure.into());
            }
        }
        Command::Emulate {
            scenario,
            seed,
            duration,
            truth,
            dir,
            gps_origin,
            json,
        } => {
            if let Some(path) = &truth {
                create_parent(path)?;
            }
            let options = emulate::EmulateOptions {
                scenario,
                simulate: simulate::SimulateOptions {
                    seed,
                    duration_s: duration,
                    ..simulate::SimulateOptions::default()
                },
                truth,
                dir,
                gps_origin,
            };
            let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
            for signal in [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM] {
                signal_hook::flag::register(signal, std::sync::Arc::clone(&stop))?;
            }
            let emulation = emulate::Emulation::start(&options)?;
            let laser = emulation.path(Device::Laser);
            let base = emulation.path(Device::Base);
            let gps = emulation.path(Device::Gps);
            let config = emulation.config_path();
            println!("laser: {}", laser.display());
            println!("base: {}", base.display());
            println!("gps: {}", gps.display());
            println!("config: {}", config.display());
            println!(
                "run: ekf live --laser {} --base {} --gps {} --config {}",
                laser.display(),
                base.display(),
                gps.display(),
                config.display()
            );
            eprintln!("ekf: the robot stands at its start until ekf live has brought up the laser and the base");
            let summary = emulation.run(&stop)?;
            if json {
                println!("{}", serde_json::to_string(&summary)?);
            } else {
                println!(
                    "{} (seed {}): {} steps, {} scans, {:.1} m driven{}{}",
                    summary.scenario,
                    summary.seed,
                    summary.steps,
                    summary.scans,
                    summary.distance_m,
                    if summary.interrupted {
                        ", interrupted"
                    } else {
                        ""
                    },
                    summary
                        .truth
                        .as_ref()
                        .map(|t| format!(", {} true poses in {t}", summary.truth_poses))
                        .unwrap_or_default()
                );
            }
        }
        Command::Map {
            action:
                MapAction::Build {
                    log,
                    out,
                    from_truth,
                    init_from_truth,
                    config,
                    json,
                },
        } => {
            let config = load_config(config.as_deref())?;
            let source = if from_truth {
                map::MapSource::Reference(Default::default())
            } else {
                map::MapSource::FirstScan { init_from_truth }
            };
            let (line_map, summary) = map::build_map(&log, &config, source)?;
            let text = line_map.to_json()?;
            create_parent(&out)?;
            std::fs::write(&out, text).map_err(|e| format!("{}: {e}", out.display()))?;
            if json {
                println!("{}", serde_json::to_string_pretty(&summary)?);
            } else {
                println!(
                    "{}: {} segments from {} scans ({} lines; {} scans skipped)",
                    out.display(),
                    summary.segments,
                    summary.scans_used,
                    summary.lines,
                    summary.scans_skipped
                );
            }
        }
        Command::Replay {
            log,
            config,
            map,
            mode,
            init_from_truth,
            global,
            out,
            tum,
            svg,
            json,
        } => {
            let config = load_config(config.as_deref())?;
            for path in [&out, &tum, &svg].into_iter().flatten() {
                create_parent(path)?;
            }
            let options = ReplayOptions {
                mode: mode.into(),
                map,
                init_from_truth,
                out_mcap: out,
                tum,
                keep_trajectories: svg.is_some(),
                global,
            };
            let bar = progress_bar();
            let mut progress = |done: u64, total: u64| {
                if let Some(b) = &bar {
                    b.set_length(total);
                    b.set_position(done);
                }
            };
            let outcome = replay::replay(&log, &config, &options, &mut progress)?;
            if let Some(b) = bar {
                b.finish_and_clear();
            }
            if json {
                println!("{}", serde_json::to_string_pretty(&outcome.summary)?);
            } else {
                print_replay_table(&outcome.summary);
            }
            if let Some(path) = &svg {
                let title = format!(
                    "{}: ekf replay --mode {}",
                    file_name(&log),
                    options.mode.name()
                );
                let map = (!outcome.map.is_empty()).then_some(&outcome.map);
                figures::write_svg_file(path, |w| figures::replay_svg(&outcome, map, &title, w))?;
            }
            if let Some(failure) = outcome.failure {
                return Err(failure.into());
            }
        }
        Command::Compare {
            log,
            config,
            map,
            init_from_truth,
            svg,
            json,
        } => {
            let config = load_config(config.as_deref())?;
            let options = compare::CompareOptions {
                map,
                init_from_truth,
            };
            let comparison = compare::compare(&log, &config, &options)?;
            if json {
                println!("{}", serde_json::to_string_pretty(&comparison)?);
            } else {
                print!("{}", comparison.to_table());
            }
            if comparison.runs().next().is_none() {
                return Err("no mode could run on this log (see the reasons above)".into());
            }
            if let Some(path) = svg {
                create_parent(&path)?;
                compare::write_svg(&comparison, &path)?;
            }
        }
        Command::Import {
            format:
                ImportFormat::Carmen {
                    input,
                    out,
                    flavour,
                    laser_max_range,
                    synthetic_compass_deg,
                    seed,
                    strict,
                    json,
                },
        } => {
            let flavour = match flavour {
                Flavour::Auto => CarmenFlavour::Auto,
                Flavour::Corrected => CarmenFlavour::Corrected,
                Flavour::Plain => CarmenFlavour::Plain,
            };
            let synthetic_compass =
                synthetic_compass_deg.map(|sigma_deg| SyntheticCompass { sigma_deg, seed });
            let options = CarmenOptions {
                flavour,
                laser_max_range,
                synthetic_compass,
                strict,
            };
            create_parent(&out)?;
            let summary = import::import_log(&input, &out, import::LogFormat::Carmen(options))?;
            print_import(&summary, &out, json)?;
        }
        Command::Import {
            format: ImportFormat::Mrpt { input, out, json },
        } => {
            create_parent(&out)?;
            let summary = import::import_log(&input, &out, import::LogFormat::Mrpt)?;
            print_import(&summary, &out, json)?;
        }
        Command::Corpus {
            paths,
            work_dir,
            config,
            global,
            json,
        } => {
            let config = load_config(config.as_deref())?;
            commands::create_output_dir(&work_dir)
                .map_err(|e| format!("{}: {e}", work_dir.display()))?;
            let logs = corpus::logs_of(&paths)?;
            let mut rows = Vec::new();
            for log in &logs {
                let row = corpus::run_log(log, &config, &work_dir, global);
                if !json {
                    eprintln!("{}: {:.1} s", row.log, row.wall_time_s);
                }
                rows.push(row);
            }
            if json {
                println!("{}", serde_json::to_string_pretty(&rows)?);
            } else {
                print!("{}", corpus::table(&rows, global));
            }
            if rows.iter().any(|r| r.error.is_some()) {
                return Err("some logs could not be run (see the table)".into());
            }
        }
        Command::Evaluate {
            estimate,
            truth,
            est_topic,
            truth_topic,
            align,
            svg,
            json,
        } => {
            let est = evaluate::load_trajectory(&estimate, est_topic.as_deref())?;
            let reference = evaluate::load_trajectory(&truth, Some(&truth_topic))?;
            let report = evaluate::evaluate(&est, &reference, align)?;
            if json {
                println!("{}", serde_json::to_string_pretty(&report)?);
            } else {
                print!("{}", report.to_table());
            }
            if let Some(path) = &svg {
                create_parent(path)?;
                let title = format!("{} against {}", file_name(&estimate), file_name(&truth));
                figures::write_svg_file(path, |w| {
                    figures::evaluation_svg(&est, &reference, align, &title, w)
                })?;
            }
        }
    }
    Ok(())
}

fn main() -> ExitCode {
    match run(Cli::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("ekf: error: {e}");
            ExitCode::FAILURE
        }
    }
}
