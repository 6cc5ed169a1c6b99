//! Fig. 11: the robot follows a rounded rectangle and a rounded triangle three ways —
//! steering by the true pose, by the laser + compass EKF, by odometry alone — and the
//! true path is compared with the commanded one.

use super::{prepare_dir, rms, write_json, ExperimentError, ExperimentOptions};
use crate::commands::simulate::{load_scenario, paper_estimator, SimulateOptions};
use crate::plot::{plot_figure, Panel, PlotOptions, TimeSeries, TrajectorySeries};
use crate::replay::Mode;
use crate::sim::{simulate, Feedback, Scenario, SimOptions, SimResult};
use crate::trajectory::Trajectory;
use serde::Serialize;

/// What steered, by name.
pub const STEERING: [&str; 3] = ["true pose", "EKF (laser + compass)", "odometry"];

/// One run along one path.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FollowRun {
    /// What steered (one of [`STEERING`]).
    pub steering: String,
    /// RMS distance of the true position from the commanded path (m).
    pub rms_deviation_m: f64,
    /// Largest distance from the path (m).
    pub max_deviation_m: f64,
    /// RMS distance per lap (m), in order; the last lap may be partial.
    pub per_lap_rms_m: Vec<f64>,
    /// Distance driven (m).
    pub distance_m: f64,
    /// Closest the robot came to a wall (m).
    pub min_clearance_m: f64,
}

/// One path and its three runs.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PathResult {
    /// The scenario (`paper`: rounded rectangle, `triangle`: rounded triangle).
    pub scenario: String,
    /// Length of one lap (m).
    pub lap_length_m: f64,
    /// Steered by the truth, the EKF, odometry.
    pub runs: Vec<FollowRun>,
    /// RMS deviation with the EKF minus that with the true pose (m).
    pub ekf_minus_truth_m: f64,
    /// Whether odometry's deviation grows: its last full lap's RMS exceeds its first's.
    pub odometry_deviation_grows: bool,
}

/// What `ekf experiment fig11` reports (`fig11.json`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Fig11Report {
    /// The seed.
    pub seed: u64,
    /// Simulated time per run (s).
    pub duration_s: f64,
    /// The figure.
    pub svg: String,
    /// Rounded rectangle (a), rounded triangle (b).
    pub paths: Vec<PathResult>,
}

impl Fig11Report {
    /// A human-readable summary: per path, the RMS deviation of each run and per lap.
    pub fn to_text(&self) -> String {
        let mut s = format!(
            "fig11: seed {}, {} s per run; figure {}\n",
            self.seed, self.duration_s, self.svg
        );
        for p in &self.paths {
            s += &format!("{} (lap {:.2} m):\n", p.scenario, p.lap_length_m);
            for r in &p.runs {
                let laps: Vec<String> = r.per_lap_rms_m.iter().map(|v| format!("{v:.3}")).collect();
                s += &format!(
                    "  steered by {:<22} RMS deviation {:.4} m (max {:.3} m), per lap [{}] m\n",
                    r.steering,
                    r.rms_deviation_m,
                    r.max_deviation_m,
                    laps.join(", ")
                );
            }
            s += &format!(
                "  EKF minus true pose: {:+.4} m; odometry's deviation grows: {}\n",
                p.ekf_minus_truth_m, p.odometry_deviation_grows
            );
        }
        s
    }
}

/// Runs the experiment with the first seed.
pub fn run(options: &ExperimentOptions) -> Result<Fig11Report, ExperimentError> {
    prepare_dir(&options.out_dir)?;
    let sim_options = SimulateOptions {
        duration_s: options.duration_s,
        ..SimulateOptions::default()
    };
    let mut paths = Vec::new();
    let mut drawn = Vec::new();
    let mut duration_s = 0.0;
    for name in ["paper", "triangle"] {
        let scenario = load_scenario(name, &sim_options)?;
        duration_s = scenario.steps() as f64 * scenario.dt;
        let runs = [
            (Feedback::Truth, None),
            (Feedback::Estimate, Some(Mode::LaserCompass)),
            (Feedback::Estimate, Some(Mode::Odometry)),
        ]
        .into_iter()
        .map(|(feedback, mode)| {
            let estimator = mode.map(paper_estimator).transpose()?;
            let sim = simulate(
                &scenario,
                &SimOptions {
                    seed: options.seed,
                    feedback,
                    estimator,
                },
                None,
            )?;
            Ok(sim)
        })
        .collect::<Result<Vec<SimResult>, ExperimentError>>()?;
        paths.push(summarize(&scenario, &runs));
        drawn.push((scenario, runs));
    }
    let svg = options.out_dir.join("fig11.svg");
    super::write_svg(&svg, |w| draw(&drawn, w))?;
    let report = Fig11Report {
        seed: options.seed,
        duration_s,
        svg: svg.display().to_string(),
        paths,
    };
    write_json(&options.out_dir.join("fig11.json"), &report)?;
    Ok(report)
}

fn summarize(scenario: &Scenario, runs: &[SimResult]) -> PathResult {
    let lap = scenario.path.length();
    let follow: Vec<FollowRun> = runs
        .iter()
        .zip(STEERING)
        .map(|(r, steering)| {
            let laps = (r.stats.distance_m / lap).ceil().max(1.0) as usize;
            let per_lap_rms_m = (0..laps)
                .map(|i| {
                    rms(r
                        .path_deviation
                        .iter()
                        .zip(&r.travelled)
                        .filter(|(_, d)| ((**d / lap) as usize).min(laps - 1) == i)
                        .map(|(v, _)| *v))
                })
                .collect();
            FollowRun {
                steering: steering.into(),
                rms_deviation_m: rms(r.path_deviation.iter().copied()),
                max_deviation_m: r.path_deviation.iter().copied().fold(0.0, f64::max),
                per_lap_rms_m,
                distance_m: r.stats.distance_m,
                min_clearance_m: r.stats.min_clearance_m,
            }
        })
        .collect();
    let full_laps = |r: &FollowRun| {
        let whole = (r.distance_m / lap).floor() as usize;
        r.per_lap_rms_m[..whole.clamp(1, r.per_lap_rms_m.len())].to_vec()
    };
    let odo = full_laps(&follow[2]);
    PathResult {
        scenario: scenario.name.clone(),
        lap_length_m: lap,
        ekf_minus_truth_m: follow[1].rms_deviation_m - follow[0].rms_deviation_m,
        odometry_deviation_grows: odo.len() >= 2 && odo[odo.len() - 1] > odo[0],
        runs: follow,
    }
}

/// The figure: the commanded path (black) with the three true paths, per path, and the
/// distance from the path over time below each.
fn draw<W: std::io::Write>(
    drawn: &[(Scenario, Vec<SimResult>)],
    writer: W,
) -> Result<(), crate::plot::PlotError> {
    let commanded: Vec<Trajectory> = drawn
        .iter()
        .map(|(s, _)| {
            let mut t = Trajectory::new();
            for (i, p) in s
                .path
                .points()
                .iter()
                .chain(s.path.points().first())
                .enumerate()
            {
                t.push(i as u64, ekf_core::Pose2::new(p.x, p.y, 0.0));
            }
            t
        })
        .collect();
    let walls: Vec<Vec<crate::plot::Wall>> = drawn
        .iter()
        .map(|(s, _)| crate::commands::figures::walls_of(&s.room.walls))
        .collect();
    let trajectories: Vec<Vec<TrajectorySeries<'_>>> = drawn
        .iter()
        .map(|(_, runs)| {
            runs.iter()
                .zip(STEERING)
                .map(|(r, name)| TrajectorySeries {
                    name,
                    trajectory: &r.truth,
                })
                .collect()
        })
        .collect();
    let deviations: Vec<Vec<Vec<(u64, f64)>>> = drawn
        .iter()
        .map(|(_, runs)| {
            runs.iter()
                .map(|r| {
                    r.truth
                        .iter()
                        .zip(&r.path_deviation)
                        .map(|(p, d)| (p.t_ns, *d))
                        .collect()
                })
                .collect()
        })
        .collect();
    let series: Vec<Vec<TimeSeries<'_>>> = deviations
        .iter()
        .map(|runs| {
            runs.iter()
                .zip(STEERING)
                .map(|(points, name)| TimeSeries { name, points })
                .collect()
        })
        .collect();
    let titles = [
        "a) Rounded rectangular path: true paths",
        "b) Rounded triangular path: true paths",
    ];
    let mut panels = Vec::new();
    for i in 0..drawn.len() {
        panels.push(Panel::Trajectories {
            title: titles[i],
            reference: Some(TrajectorySeries {
                name: "commanded path",
                trajectory: &commanded[i],
            }),
            estimates: &trajectories[i],
            walls: &walls[i],
            markers: &[],
        });
    }
    for s in &series {
        panels.push(Panel::ErrorsOverTime {
            title: "Distance of the true position from the path",
            series: s,
            y_desc: "distance from path [m]",
            markers: &[],
        });
    }
    let options = PlotOptions {
        title: "Fig. 11: following paths steered by the truth, the EKF, odometry".into(),
        width: 1500,
        height: 1150,
    };
    plot_figure(writer, &panels, drawn.len(), &options)
}
