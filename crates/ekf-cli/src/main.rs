//! `ekf`: localization from wheel odometry, a compass and laser lines. See `ekf --help`.
//!
//! This file only parses arguments, calls the library and prints what it returns.

use clap::{Parser, Subcommand};
use ekf_cli::commands::evaluate;
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

fn run(cli: Cli) -> Result<(), Box<dyn std::error::Error>> {
    match cli.command {
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
