//! Fig. 9/10: the paper's scenario run once per seed, its log replayed in the four
//! estimator configurations ([`crate::commands::compare`]), and the laser + compass
//! filter's consistency: its NEES over the seeds against the chi-square band.
//!
//! The NEES comes from the same filter running inside the simulation on the same
//! measurements (the robot steers by the truth, so the run does not depend on it); the
//! replay of the log starts where that filter started (the truth plus an error drawn from
//! the initial covariance) and fuses the same readings in the same order.

use super::{prepare_dir, write_json, ExperimentError, ExperimentOptions};
use crate::commands::compare::{compare, render_svg, CompareOptions, ModeOutcome};
use crate::commands::simulate::{load_scenario, paper_estimator, SimulateOptions};
use crate::config::Config;
use crate::replay::Mode;
use crate::sim::{simulate, Feedback, LogRecorder, Nees, SimOptions};
use ekf_core::chi_square_quantile;
use serde::Serialize;

/// One mode's accuracy in one seed's run.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ModeAccuracy {
    /// `odometry`, `compass`, `laser` or `laser+compass`.
    pub mode: String,
    /// Position RMSE (m).
    pub position_rmse_m: f64,
    /// RMSE of the x error (m), Fig. 10 top.
    pub x_rmse_m: f64,
    /// RMSE of the y error (m), Fig. 10 bottom.
    pub y_rmse_m: f64,
    /// Heading RMSE (degrees).
    pub heading_rmse_deg: f64,
}

/// One seed.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SeedResult {
    /// The seed.
    pub seed: u64,
    /// The four modes in the paper's order.
    pub modes: Vec<ModeAccuracy>,
    /// Odometry has the largest position RMSE and laser + compass the smallest.
    pub ordering_holds: bool,
    /// Time average of the laser + compass filter's NEES.
    pub nees_mean: f64,
    /// Compass outliers in the run.
    pub compass_outliers: u64,
    /// Of them, fused by the laser + compass filter (the gate should reject all).
    pub compass_outliers_fused: u64,
}

/// A mode over all seeds.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ModeSummary {
    /// The mode.
    pub mode: String,
    /// Mean over seeds of the position RMSE (m).
    pub position_rmse_m_mean: f64,
    /// Largest position RMSE of a seed (m).
    pub position_rmse_m_worst: f64,
    /// Mean over seeds of the heading RMSE (degrees).
    pub heading_rmse_deg_mean: f64,
    /// Largest heading RMSE of a seed (degrees).
    pub heading_rmse_deg_worst: f64,
}

/// The consistency test (Bar-Shalom, Li, Kirubarajan 2001, §5.4.2): with `N` runs, at
/// each time step `N` times the ensemble-average NEES of an `n`-dimensional error is
/// χ²(nN) for a consistent filter, so that average lies in
/// `[χ²₀.₀₂₅(nN)/N, χ²₀.₉₇₅(nN)/N]` with probability 0.95: about 95 % of the steps should
/// be inside. The time average of the ensemble average is reported too; held against
/// the same band it is a lenient check (a time average varies much less than one step's
/// value).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct NeesSummary {
    /// Runs.
    pub runs: u32,
    /// Degrees of freedom `n` of one run's NEES: 3 for the pose, 2 for the position,
    /// 1 for the heading.
    pub dof: u32,
    /// Average NEES over all steps of all runs (`n` for a consistent filter).
    pub mean: f64,
    /// The 95 % band of the ensemble average.
    pub band: [f64; 2],
    /// Whether `mean` lies in the band.
    pub inside: bool,
    /// Fraction of time steps whose ensemble-average NEES lies in the band (about 0.95
    /// for a consistent filter).
    pub steps_inside: f64,
    /// Fraction of steps above the band (the filter overconfident there).
    pub steps_above: f64,
    /// Fraction of steps below the band (the filter too cautious there).
    pub steps_below: f64,
}

/// What `ekf experiment fig9` reports (`fig9.json`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Fig9Report {
    /// The scenario.
    pub scenario: String,
    /// Simulated time per run (s).
    pub duration_s: f64,
    /// The first seed's log (replayable with `ekf replay`).
    pub log: String,
    /// The figure.
    pub svg: String,
    /// Each mode over all seeds.
    pub modes: Vec<ModeSummary>,
    /// Seeds in which the paper's ordering holds, of all seeds.
    pub ordering_holds: [u32; 2],
    /// Consistency of the laser + compass filter: its pose.
    pub nees: NeesSummary,
    /// ... its position alone.
    pub nees_position: NeesSummary,
    /// ... its heading alone.
    pub nees_heading: NeesSummary,
    /// Compass outliers over all runs, and how many the laser + compass filter fused.
    pub compass_outliers: [u64; 2],
    /// Every seed.
    pub seeds: Vec<SeedResult>,
}

impl Fig9Report {
    /// A human-readable summary: the mean accuracy per mode, the ordering and the NEES.
    pub fn to_text(&self) -> String {
        let mut s = format!(
            "fig9: scenario {}, {} seeds of {} s; figure {}\n{:<14} {:>12} {:>12} {:>14} {:>14}\n",
            self.scenario,
            self.seeds.len(),
            self.duration_s,
            self.svg,
            "mode",
            "RMSE m mean",
            "RMSE m worst",
            "head. deg mean",
            "head. deg worst"
        );
        for m in &self.modes {
            s += &format!(
                "{:<14} {:>12.4} {:>12.4} {:>14.3} {:>14.3}\n",
                m.mode,
                m.position_rmse_m_mean,
                m.position_rmse_m_worst,
                m.heading_rmse_deg_mean,
                m.heading_rmse_deg_worst
            );
        }
        s += &format!(
            "paper's ordering (odometry worst, laser+compass best) in {} of {} seeds\nNEES of laser+compass over {} runs (95 % of steps inside the band expected):\n",
            self.ordering_holds[0], self.ordering_holds[1], self.nees.runs,
        );
        for (part, n) in [
            ("pose", &self.nees),
            ("position", &self.nees_position),
            ("heading", &self.nees_heading),
        ] {
            s += &format!(
                "  {part:<8} ({} dof): per-step average inside the 95 % band {:.2}..{:.2} at {:.0} % of steps (above {:.0} %, below {:.0} %); time average {:.2} ({} the band)\n",
                n.dof,
                n.band[0],
                n.band[1],
                100.0 * n.steps_inside,
                100.0 * n.steps_above,
                100.0 * n.steps_below,
                n.mean,
                if n.inside { "inside" } else { "outside" },
            );
        }
        s += &format!(
            "compass outliers: {} injected, {} fused\n",
            self.compass_outliers[0], self.compass_outliers[1]
        );
        s
    }
}

/// Runs the experiment.
pub fn run(options: &ExperimentOptions) -> Result<Fig9Report, ExperimentError> {
    if options.seeds == 0 {
        return Err(ExperimentError::Option("--seeds must be at least 1".into()));
    }
    let end = options
        .seed
        .checked_add(u64::from(options.seeds))
        .ok_or_else(|| ExperimentError::Option("--seed + --seeds overflows 64 bits".into()))?;
    prepare_dir(&options.out_dir)?;
    let scenario = load_scenario(
        "paper",
        &SimulateOptions {
            duration_s: options.duration_s,
            ..SimulateOptions::default()
        },
    )?;
    let config = Config::preset("paper-robot")?;
    let first_log = options.out_dir.join("fig9-run.mcap");
    let scratch_log = options.out_dir.join("fig9-scratch.mcap");
    let svg = options.out_dir.join("fig9.svg");
    let mut seeds = Vec::new();
    let mut nees_runs: Vec<Vec<Nees>> = Vec::new();
    for seed in options.seed..end {
        let log = if seed == options.seed {
            &first_log
        } else {
            &scratch_log
        };
        let mut recorder = LogRecorder::create(log, &scenario, seed)?;
        let sim = simulate(
            &scenario,
            &SimOptions {
                seed,
                feedback: Feedback::Truth,
                estimator: Some(paper_estimator(Mode::LaserCompass)?),
            },
            Some(&mut recorder),
        );
        recorder.finish()?;
        let sim = sim?;
        // The replays start where the in-loop filter did (the truth plus the seed's
        // initial error), so they fuse exactly what it fused.
        let mut config = config.clone();
        if let Some(start) = sim.initial_estimate {
            (config.initial.x, config.initial.y, config.initial.theta) =
                (start.x, start.y, start.theta);
        }
        let comparison = compare(
            log,
            &config,
            &CompareOptions {
                map: None,
                init_from_truth: false,
            },
        )?;
        if seed == options.seed {
            super::write_svg(&svg, |w| render_svg(&comparison, w))?;
        }
        let mut modes = Vec::new();
        for m in &comparison.modes {
            match &m.outcome {
                ModeOutcome::Ran(r) => modes.push(ModeAccuracy {
                    mode: m.mode.clone(),
                    position_rmse_m: r.accuracy.position_rmse_m,
                    x_rmse_m: r.accuracy.x_rmse_m,
                    y_rmse_m: r.accuracy.y_rmse_m,
                    heading_rmse_deg: r.accuracy.heading_rmse_deg,
                }),
                ModeOutcome::Unavailable { reason } => {
                    return Err(ExperimentError::Setup(format!(
                        "seed {seed}: mode {} did not run: {reason}",
                        m.mode
                    )))
                }
            }
        }
        let rmse = |name: &str| {
            modes
                .iter()
                .find(|m| m.mode == name)
                .map_or(f64::NAN, |m| m.position_rmse_m)
        };
        let (odo, best) = (rmse("odometry"), rmse("laser+compass"));
        let ordering_holds = modes
            .iter()
            .filter(|m| m.mode != "odometry")
            .all(|m| m.position_rmse_m < odo)
            && modes
                .iter()
                .filter(|m| m.mode != "laser+compass")
                .all(|m| m.position_rmse_m > best);
        seeds.push(SeedResult {
            seed,
            modes,
            ordering_holds,
            nees_mean: sim.nees.iter().map(|n| n.pose).sum::<f64>() / sim.nees.len().max(1) as f64,
            compass_outliers: sim.stats.compass_outliers,
            compass_outliers_fused: sim.stats.compass_outliers_fused,
        });
        nees_runs.push(sim.nees);
    }
    // The scratch log only served the replays of the later seeds.
    let _ = std::fs::remove_file(&scratch_log);
    let report = Fig9Report {
        scenario: scenario.name.clone(),
        duration_s: scenario.steps() as f64 * scenario.dt,
        log: first_log.display().to_string(),
        svg: svg.display().to_string(),
        modes: summarize_modes(&seeds),
        ordering_holds: [
            seeds.iter().filter(|s| s.ordering_holds).count() as u32,
            options.seeds,
        ],
        nees: nees_summary(&nees_runs, 3, |n| n.pose)?,
        nees_position: nees_summary(&nees_runs, 2, |n| n.position)?,
        nees_heading: nees_summary(&nees_runs, 1, |n| n.heading)?,
        compass_outliers: [
            seeds.iter().map(|s| s.compass_outliers).sum(),
            seeds.iter().map(|s| s.compass_outliers_fused).sum(),
        ],
        seeds,
    };
    write_json(&options.out_dir.join("fig9.json"), &report)?;
    Ok(report)
}

fn summarize_modes(seeds: &[SeedResult]) -> Vec<ModeSummary> {
    Mode::ALL
        .iter()
        .map(|mode| {
            let rows: Vec<&ModeAccuracy> = seeds
                .iter()
                .filter_map(|s| s.modes.iter().find(|m| m.mode == mode.name()))
                .collect();
            let n = rows.len().max(1) as f64;
            let worst = |f: fn(&ModeAccuracy) -> f64| rows.iter().map(|m| f(m)).fold(0.0, f64::max);
            ModeSummary {
                mode: mode.name().into(),
                position_rmse_m_mean: rows.iter().map(|m| m.position_rmse_m).sum::<f64>() / n,
                position_rmse_m_worst: worst(|m| m.position_rmse_m),
                heading_rmse_deg_mean: rows.iter().map(|m| m.heading_rmse_deg).sum::<f64>() / n,
                heading_rmse_deg_worst: worst(|m| m.heading_rmse_deg),
            }
        })
        .collect()
}

/// The NEES test over runs of equal length on the `dof`-dimensional part `part` of each
/// step's [`Nees`].
pub fn nees_summary(
    runs: &[Vec<Nees>],
    dof: u32,
    part: fn(&Nees) -> f64,
) -> Result<NeesSummary, ExperimentError> {
    let n = runs.len() as u32;
    let steps = runs.iter().map(Vec::len).min().unwrap_or(0);
    if n == 0 || steps == 0 {
        return Err(ExperimentError::Setup("no NEES values".into()));
    }
    let quantile = |p| {
        chi_square_quantile(p, dof * n)
            .map(|q| q / f64::from(n))
            .map_err(|e| ExperimentError::Setup(format!("chi-square quantile: {e}")))
    };
    let band = [quantile(0.025)?, quantile(0.975)?];
    let ensemble: Vec<f64> = (0..steps)
        .map(|k| runs.iter().map(|r| part(&r[k])).sum::<f64>() / f64::from(n))
        .collect();
    let mean = ensemble.iter().sum::<f64>() / steps as f64;
    let inside = |v: f64| (band[0]..=band[1]).contains(&v);
    let fraction = |test: &dyn Fn(f64) -> bool| {
        ensemble.iter().filter(|v| test(**v)).count() as f64 / steps as f64
    };
    Ok(NeesSummary {
        runs: n,
        dof,
        mean,
        band,
        inside: inside(mean),
        steps_inside: fraction(&|v| inside(v)),
        steps_above: fraction(&|v| v > band[1]),
        steps_below: fraction(&|v| v < band[0]),
    })
}
