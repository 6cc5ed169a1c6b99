//! `ekf`: localization from wheel odometry, a compass and laser lines. See `ekf --help`.
//!
//! This file only dispatches: [`args`] holds what clap parses, each command below turns
//! its arguments into the library's options, calls the library and prints what it
//! returns through the result's `Display` (or `--json`).

mod args;
mod output;

use args::{
    Cli, CliMode, CliSteering, Command, CompareArgs, ConfigArgs, CorpusArgs, EmulateArgs,
    EvaluateArgs, ExperimentArgs, Figure, Flavour, ImportCarmenArgs, ImportFormat, ImportMrptArgs,
    LiveArgs, MapAction, MapBuildArgs, MapCompareArgs, MapExportGridArgs, MapImportGridArgs,
    MapPlotArgs, ReplayArgs, SimulateArgs,
};
use clap::Parser;
use ekf_cli::commands::{
    self, compare, corpus, emulate, evaluate, experiment, figures, grid, import, map, simulate,
};
use ekf_cli::config::{Config, DEFAULT_TOML};
use ekf_cli::import::{CarmenFlavour, CarmenOptions, SyntheticCompass};
use ekf_cli::live;
use ekf_cli::replay::{self, Mode, ReplayOptions};
use ekf_ros::map_compare;
use output::{emit, emit_line, Closed};
use serde::Serialize;
use std::io::IsTerminal;
use std::path::Path;
use std::process::ExitCode;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

/// What a command returns: its error is printed as `ekf: error: …`.
type Outcome = Result<(), Box<dyn std::error::Error>>;

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
fn file_name(path: &Path) -> String {
    path.file_name()
        .unwrap_or(path.as_os_str())
        .to_string_lossy()
        .into_owned()
}

/// Creates the folder an output file goes into, so `--out results/run.mcap` just works.
fn create_parent(path: &Path) -> Result<(), String> {
    match path.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => {
            commands::create_output_dir(dir).map_err(|e| format!("{}: {e}", dir.display()))
        }
        _ => Ok(()),
    }
}

/// The configuration file, or the documented defaults without one.
fn load_config(path: Option<&Path>) -> Result<Config, Box<dyn std::error::Error>> {
    Ok(match path {
        Some(p) => Config::load(p)?,
        None => Config::default(),
    })
}

/// A flag that SIGINT or SIGTERM sets, for the commands that run until stopped.
fn stop_on_signals() -> std::io::Result<Arc<AtomicBool>> {
    let stop = Arc::new(AtomicBool::new(false));
    for signal in [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM] {
        signal_hook::flag::register(signal, Arc::clone(&stop))?;
    }
    Ok(stop)
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

/// Prints `value` as pretty JSON with `--json`, else `text` (which ends its own lines).
fn print_result(value: &impl Serialize, json: bool, text: impl std::fmt::Display) -> Outcome {
    if json {
        emit_line(serde_json::to_string_pretty(value)?)
    } else {
        emit(text)
    }
}

fn main() -> ExitCode {
    let outcome = match Cli::parse().command {
        Command::Replay(a) => replay_command(a),
        Command::Compare(a) => compare_command(a),
        Command::Experiment(a) => experiment_command(a),
        Command::Config(a) => config_command(a),
        Command::Simulate(a) => simulate_command(a),
        Command::Live(a) => live_command(a),
        Command::Emulate(a) => emulate_command(a),
        Command::Map { action } => map_command(action),
        Command::Import {
            format: ImportFormat::Carmen(a),
        } => import_carmen_command(a),
        Command::Import {
            format: ImportFormat::Mrpt(a),
        } => import_mrpt_command(a),
        Command::Corpus(a) => corpus_command(a),
        Command::Evaluate(a) => evaluate_command(a),
    };
    match outcome {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) if e.is::<Closed>() => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("ekf: error: {e}");
            ExitCode::FAILURE
        }
    }
}

fn replay_command(a: ReplayArgs) -> Outcome {
    let config = load_config(a.inputs.config.as_deref())?;
    for path in [&a.out, &a.tum, &a.svg].into_iter().flatten() {
        create_parent(path)?;
    }
    let options = ReplayOptions {
        mode: a.mode.into(),
        map: a.inputs.map,
        init_from_truth: a.init_from_truth,
        out_mcap: a.out,
        tum: a.tum,
        keep_trajectories: a.svg.is_some(),
        global: a.global,
        grow_map: a.grow_map,
    };
    let bar = progress_bar();
    let mut progress = |done: u64, total: u64| {
        if let Some(b) = &bar {
            b.set_length(total);
            b.set_position(done);
        }
    };
    let outcome = replay::replay(&a.log, &config, &options, &mut progress)?;
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    if let Some(path) = &a.write_map {
        write_map(&outcome.map, path)?;
    }
    print_result(&outcome.summary, a.json, &outcome.summary)?;
    if let Some(path) = &a.svg {
        let title = format!(
            "{}: ekf replay --mode {}",
            file_name(&a.log),
            options.mode.name()
        );
        let map = (!outcome.map.is_empty()).then_some(&outcome.map);
        figures::write_svg_file(path, |w| figures::replay_svg(&outcome, map, &title, w))?;
    }
    match outcome.failure {
        Some(failure) => Err(failure.into()),
        None => Ok(()),
    }
}

fn compare_command(a: CompareArgs) -> Outcome {
    let config = load_config(a.inputs.config.as_deref())?;
    let options = compare::CompareOptions {
        map: a.inputs.map,
        init_from_truth: a.init_from_truth,
    };
    let comparison = compare::compare(&a.log, &config, &options)?;
    print_result(&comparison, a.json, comparison.to_table())?;
    if comparison.runs().next().is_none() {
        return Err("no mode could run on this log (see the reasons above)".into());
    }
    if let Some(path) = a.svg {
        create_parent(&path)?;
        compare::write_svg(&comparison, &path)?;
    }
    Ok(())
}

fn experiment_command(a: ExperimentArgs) -> Outcome {
    let options = experiment::ExperimentOptions {
        out_dir: a.out_dir,
        seed: a.seed,
        seeds: a.seeds,
        duration_s: a.duration,
    };
    match a.figure {
        Figure::Fig9 => {
            let r = experiment::fig9::run(&options)?;
            print_result(&r, a.json, r.to_text())
        }
        Figure::Fig11 => {
            let r = experiment::fig11::run(&options)?;
            print_result(&r, a.json, r.to_text())
        }
        Figure::Fig12 => {
            let r = experiment::fig12::run(&options)?;
            print_result(&r, a.json, r.to_text())
        }
    }
}

fn config_command(a: ConfigArgs) -> Outcome {
    match a.preset {
        None => emit(DEFAULT_TOML)?,
        Some(name) => emit(Config::preset_text(&name)?)?,
    }
    Ok(())
}

fn simulate_command(a: SimulateArgs) -> Outcome {
    let options = simulate::SimulateOptions {
        seed: a.seed,
        duration_s: a.duration,
        steering: match a.steer_by {
            CliSteering::Truth => simulate::Steering::Truth,
            CliSteering::Ekf => simulate::Steering::Ekf,
            CliSteering::Odometry => simulate::Steering::Odometry,
        },
        resolution_deg: a.resolution,
        slips_per_minute: a.slips_per_minute,
        compass_bias_deg: a.compass_bias,
        compass_outliers: a.compass_outliers,
    };
    let scenario = simulate::load_scenario(&a.scenario, &options)?;
    create_parent(&a.out)?;
    let (_, summary) = simulate::run_simulation(&scenario, &options, Some(&a.out))?;
    print_result(&summary, a.json, &summary)
}

fn live_command(a: LiveArgs) -> Outcome {
    let config = load_config(a.inputs.config.as_deref())?;
    if let Some(path) = &a.record {
        create_parent(path)?;
    }
    let options = live::LiveOptions {
        laser: a.laser,
        base: a.base,
        gps: a.gps,
        record: a.record,
        map: a.inputs.map,
        mode: a.mode.into(),
    };
    let stop = stop_on_signals()?;
    // A reader of the poses that goes away stops the run as Ctrl-C does, so that the
    // recording is closed properly.
    let closed = Arc::clone(&stop);
    let outcome = live::run(&config, &options, stop, &mut |event| {
        let printed = match event.pose_json() {
            Some(line) if a.json => emit_line(line),
            Some(_) => emit_line(event),
            None => {
                eprintln!("ekf: {event}");
                Ok(())
            }
        };
        if printed.is_err() {
            closed.store(true, std::sync::atomic::Ordering::SeqCst);
        }
    })?;
    if a.json {
        emit_line(serde_json::to_string(&outcome.summary)?)?;
    } else {
        emit(&outcome.summary)?;
    }
    match outcome.failure {
        Some(failure) => Err(failure.into()),
        None => Ok(()),
    }
}

fn emulate_command(a: EmulateArgs) -> Outcome {
    if let Some(path) = &a.truth {
        create_parent(path)?;
    }
    let options = emulate::EmulateOptions {
        scenario: a.scenario,
        simulate: simulate::SimulateOptions {
            seed: a.seed,
            duration_s: a.duration,
            ..simulate::SimulateOptions::default()
        },
        truth: a.truth,
        dir: a.dir,
        gps_origin: a.gps_origin,
    };
    let stop = stop_on_signals()?;
    let emulation = emulate::Emulation::start(&options)?;
    emit(emulation.connection())?;
    eprintln!(
        "ekf: the robot stands at its start until ekf live has brought up the laser and the base"
    );
    let summary = emulation.run(&stop)?;
    if a.json {
        emit_line(serde_json::to_string(&summary)?)?;
    } else {
        emit(&summary)?;
    }
    Ok(())
}

fn map_command(action: MapAction) -> Outcome {
    match action {
        MapAction::Build(a) => map_build_command(a),
        MapAction::ImportGrid(a) => map_import_grid_command(a),
        MapAction::ExportGrid(a) => map_export_grid_command(a),
        MapAction::Compare(a) => map_compare_command(a),
        MapAction::Plot(a) => map_plot_command(a),
    }
}

/// Writes `map` as JSON to `path`, creating its folder.
fn write_map(map: &lrf_lines::LineMap, path: &Path) -> Outcome {
    let text = map.to_json()?;
    create_parent(path)?;
    std::fs::write(path, text).map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(())
}

fn map_build_command(a: MapBuildArgs) -> Outcome {
    let config = load_config(a.config.as_deref())?;
    if a.slam {
        return map_build_slam(&a, &config);
    }
    let source = if a.from_truth {
        map::MapSource::Reference(Default::default())
    } else {
        map::MapSource::FirstScan {
            init_from_truth: a.init_from_truth,
        }
    };
    let (line_map, summary) = map::build_map(&a.log, &config, source)?;
    write_map(&line_map, &a.out)?;
    print_result(
        &summary,
        a.json,
        format_args!("{}: {summary}", a.out.display()),
    )
}

/// `ekf map build --slam`: the map, the corrected trajectory, the summary; what came
/// before a damaged part of the log is written before the error is reported.
fn map_build_slam(a: &MapBuildArgs, config: &ekf_ros::config::Config) -> Outcome {
    let bar = progress_bar();
    let mut progress = |done: u64, total: u64| {
        if let Some(b) = &bar {
            b.set_length(total);
            b.set_position(done);
        }
    };
    let outcome = ekf_ros::slam::build_slam_map(&a.log, config, &mut progress)?;
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    write_map(&outcome.map, &a.out)?;
    if let Some(path) = &a.tum {
        create_parent(path)?;
        ekf_ros::tum::write_tum_file(path, &outcome.trajectory)?;
    }
    let summary = &outcome.summary;
    print_result(
        summary,
        a.json,
        format_args!("{}: {summary}", a.out.display()),
    )?;
    match outcome.failure {
        Some(failure) => Err(failure.into()),
        None => Ok(()),
    }
}

fn map_import_grid_command(a: MapImportGridArgs) -> Outcome {
    let config = load_config(a.config.as_deref())?;
    let params = grid::GridImportParams {
        scan_spacing: a.scan_spacing,
        min_sightings: a.min_sightings,
        max_range: a.max_range,
        ..Default::default()
    };
    let (line_map, summary) = grid::import(&a.yaml, &config.localizer.extraction, &params)?;
    write_map(&line_map, &a.out)?;
    print_result(
        &summary,
        a.json,
        format_args!("{}: {summary}", a.out.display()),
    )
}

fn map_export_grid_command(a: MapExportGridArgs) -> Outcome {
    let line_map = ekf_ros::replay::load_map(&a.map)?;
    create_parent(&a.out)?;
    let summary = grid::export(&line_map, &a.map, &a.out, a.resolution, a.margin)?;
    print_result(
        &summary,
        a.json,
        format_args!("{}: {summary}", a.out.display()),
    )
}

fn map_compare_command(a: MapCompareArgs) -> Outcome {
    let line_map = ekf_ros::replay::load_map(&a.map)?;
    let reference = ekf_ros::replay::load_map(&a.reference)?;
    let params = Default::default();
    let identity = ekf_core::Pose2::new(0.0, 0.0, 0.0);
    let comparison = match a.align {
        true => ekf_ros::map_search::aligned_comparison(&line_map, &reference, &params),
        false => map_compare::compare(&line_map, &reference, &identity, &params),
    };
    print_result(&comparison, a.json, &comparison)
}

fn map_plot_command(a: MapPlotArgs) -> Outcome {
    let line_map = ekf_ros::replay::load_map(&a.map)?;
    let trajectories = a
        .trajectory
        .iter()
        .map(|p| Ok((file_name(p), ekf_ros::tum::read_tum_file(p)?)))
        .collect::<Result<Vec<_>, Box<dyn std::error::Error>>>()?;
    let mut svg = Vec::new();
    commands::map_plot::plot_map(&mut svg, &line_map, &trajectories, &file_name(&a.map))
        .map_err(|e| format!("{}: {e}", a.svg.display()))?;
    create_parent(&a.svg)?;
    std::fs::write(&a.svg, svg).map_err(|e| format!("{}: {e}", a.svg.display()))?;
    emit_line(format_args!(
        "{}: {} walls, {} trajectories",
        a.svg.display(),
        line_map.len(),
        trajectories.len()
    ))
}

fn import_carmen_command(a: ImportCarmenArgs) -> Outcome {
    let flavour = match a.flavour {
        Flavour::Auto => CarmenFlavour::Auto,
        Flavour::Corrected => CarmenFlavour::Corrected,
        Flavour::Plain => CarmenFlavour::Plain,
    };
    let options = CarmenOptions {
        flavour,
        laser_max_range: a.laser_max_range,
        synthetic_compass: a.synthetic_compass_deg.map(|sigma_deg| SyntheticCompass {
            sigma_deg,
            seed: a.seed,
        }),
        strict: a.strict,
    };
    import_to(&a.input, &a.out, import::LogFormat::Carmen(options), a.json)
}

fn import_mrpt_command(a: ImportMrptArgs) -> Outcome {
    import_to(&a.input, &a.out, import::LogFormat::Mrpt, a.json)
}

/// Imports `input` into the bag `out` and prints the summary; the repairs are warnings on
/// stderr (in `--json` they are part of the object).
fn import_to(input: &Path, out: &Path, format: import::LogFormat, json: bool) -> Outcome {
    create_parent(out)?;
    let summary = import::import_log(input, out, format)?;
    print_result(&summary, json, format_args!("{}: {summary}", out.display()))?;
    if !json {
        for line in import::repair_lines(&summary.stats) {
            eprintln!("warning: {line}");
        }
    }
    Ok(())
}

fn corpus_command(a: CorpusArgs) -> Outcome {
    let config = load_config(a.config.as_deref())?;
    commands::create_output_dir(&a.work_dir)
        .map_err(|e| format!("{}: {e}", a.work_dir.display()))?;
    let logs = corpus::logs_of(&a.paths)?;
    let mut rows = Vec::new();
    for log in &logs {
        let row = corpus::run_log(log, &config, &a.work_dir, a.global);
        if !a.json {
            eprintln!("{}: {:.1} s", row.log, row.wall_time_s);
        }
        rows.push(row);
    }
    print_result(&rows, a.json, corpus::table(&rows, a.global))?;
    if rows.iter().any(|r| r.error.is_some()) {
        return Err("some logs could not be run (see the table)".into());
    }
    Ok(())
}

fn evaluate_command(a: EvaluateArgs) -> Outcome {
    let est = evaluate::load_trajectory(&a.estimate, a.est_topic.as_deref())?;
    let reference = evaluate::load_trajectory(&a.truth, Some(&a.truth_topic))?;
    let report = evaluate::evaluate(&est, &reference, a.align)?;
    print_result(&report, a.json, report.to_table())?;
    if let Some(path) = &a.svg {
        create_parent(path)?;
        let title = format!("{} against {}", file_name(&a.estimate), file_name(&a.truth));
        figures::write_svg_file(path, |w| {
            figures::evaluation_svg(&est, &reference, a.align, &title, w)
        })?;
    }
    Ok(())
}
