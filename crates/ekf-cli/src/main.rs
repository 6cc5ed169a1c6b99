//! `ekf`: localization from wheel odometry, a compass and laser lines. See `ekf --help`.
//!
//! This file only parses arguments, calls the library and prints what it returns.

use clap::ValueEnum;
use clap::{Parser, Subcommand};
use ekf_cli::commands::{evaluate, import};
use ekf_cli::import::{CarmenFlavour, CarmenOptions, SyntheticCompass};
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
    /// Convert a CARMEN or MRPT text log into a ROS 2 bag (MCAP) with /odom, /scan,
    /// /tf_static, /ground_truth (corrected CARMEN logs) and optionally a synthetic /compass.
    Import {
        #[command(subcommand)]
        format: ImportFormat,
    },
    /// Absolute and relative pose errors of a trajectory against a reference, as `evo`
    /// computes them (same frame, no alignment unless --align).
    Evaluate {
        /// The estimated trajectory (TUM file).
        estimate: PathBuf,
        /// The reference trajectory (TUM file).
        #[arg(long)]
        truth: PathBuf,
        /// Align the estimate to the reference first (rigid SE(2) Umeyama, as `evo -a`).
        #[arg(long)]
        align: bool,
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
        /// The bag to write.
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
        /// Print the summary as JSON.
        #[arg(long)]
        json: bool,
    },
    /// MRPT's text export (ODOM, RAWSCAN).
    Mrpt {
        /// The MRPT text log.
        input: PathBuf,
        /// The bag to write.
        #[arg(long)]
        out: PathBuf,
        /// Print the summary as JSON.
        #[arg(long)]
        json: bool,
    },
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
    }
    Ok(())
}

fn run(cli: Cli) -> Result<(), Box<dyn std::error::Error>> {
    match cli.command {
        Command::Import {
            format:
                ImportFormat::Carmen {
                    input,
                    out,
                    flavour,
                    laser_max_range,
                    synthetic_compass_deg,
                    seed,
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
            };
            let summary = import::import_log(&input, &out, import::LogFormat::Carmen(options))?;
            print_import(&summary, &out, json)?;
        }
        Command::Import {
            format: ImportFormat::Mrpt { input, out, json },
        } => {
            let summary = import::import_log(&input, &out, import::LogFormat::Mrpt)?;
            print_import(&summary, &out, json)?;
        }
        Command::Evaluate {
            estimate,
            truth,
            align,
            json,
        } => {
            let est = evaluate::load_trajectory(&estimate)?;
            let reference = evaluate::load_trajectory(&truth)?;
            let report = evaluate::evaluate(&est, &reference, align)?;
            if json {
                println!("{}", serde_json::to_string_pretty(&report)?);
            } else {
                print!("{}", report.to_table());
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
