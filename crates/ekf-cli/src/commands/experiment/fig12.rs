//! Fig. 12: the robot drives round its room close to the walls of the map extracted from
//! its first scan, steering by the laser + compass EKF that uses that map.
//!
//! The robot starts near a corner facing the room's diagonal, so its 180° first scan
//! sees all four walls; the commanded loop keeps [`CLEARANCE`] from each wall of that
//! map (the longest wall on each side).

use super::{prepare_dir, rms, write_json, ExperimentError, ExperimentOptions};
use crate::commands::simulate::{load_scenario, paper_estimator, SimulateOptions};
use crate::plot::{plot_figure, Panel, PlotOptions, TimeSeries, TrajectorySeries, Wall};
use crate::replay::Mode;
use crate::sim::rng::{SimRng, Stream};
use crate::sim::{simulate, Feedback, Path, SimOptions};
use crate::trajectory::Trajectory;
use ekf_core::{angle_diff, Pose2};
use lrf_lines::{LaserScan, LineExtractor, LineMap};
use nalgebra::{Matrix2, Point2, Vector2};
use serde::Serialize;

/// Distance the commanded loop keeps from the map's walls (m).
pub const CLEARANCE: f64 = 0.6;
/// Corner radius of the loop (m).
const CORNER_RADIUS: f64 = 0.4;

/// What `ekf experiment fig12` reports (`fig12.json`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Fig12Report {
    /// The seed.
    pub seed: u64,
    /// Simulated time (s).
    pub duration_s: f64,
    /// The figure.
    pub svg: String,
    /// Walls in the first-scan map.
    pub map_segments: usize,
    /// Distance the loop keeps from the map's walls (m).
    pub clearance_m: f64,
    /// Length of one lap (m).
    pub lap_length_m: f64,
    /// Distance driven (m).
    pub distance_m: f64,
    /// RMS distance of the true position from the commanded loop (m).
    pub rms_deviation_m: f64,
    /// Largest distance from the loop (m).
    pub max_deviation_m: f64,
    /// Closest the robot came to a real wall (m).
    pub min_clearance_m: f64,
    /// Position RMSE of the EKF against the truth (m).
    pub position_rmse_m: f64,
    /// Heading RMSE of the EKF (degrees).
    pub heading_rmse_deg: f64,
    /// Laser lines fused.
    pub lines_fused: u64,
}

impl Fig12Report {
    /// A human-readable summary.
    pub fn to_text(&self) -> String {
        format!(
            "fig12: seed {}, {} s; figure {}\nfirst-scan map: {} walls; loop {} m inside them, {:.2} m per lap; driven {:.1} m\ndistance from the loop: RMS {:.3} m, max {:.3} m; closest to a wall {:.2} m\nEKF against the truth: position RMSE {:.4} m, heading RMSE {:.3} deg, {} lines fused\n",
            self.seed,
            self.duration_s,
            self.svg,
            self.map_segments,
            self.clearance_m,
            self.lap_length_m,
            self.distance_m,
            self.rms_deviation_m,
            self.max_deviation_m,
            self.min_clearance_m,
            self.position_rmse_m,
            self.heading_rmse_deg,
            self.lines_fused
        )
    }
}

/// Runs the experiment with the first seed.
pub fn run(options: &ExperimentOptions) -> Result<Fig12Report, ExperimentError> {
    prepare_dir(&options.out_dir)?;
    let mut scenario = load_scenario(
        "walls",
        &SimulateOptions {
            duration_s: options.duration_s,
            ..SimulateOptions::default()
        },
    )?;
    scenario.start = Pose2::new(1.3, 1.0, std::f64::consts::FRAC_PI_4);
    let mut estimator = paper_estimator(Mode::LaserCompass)?;
    // The first scan of the run (the laser's noise stream starts with it), its lines
    // placed at the start pose: the paper's global map.
    let laser = scenario.laser;
    let ranges = laser.scan(
        &scenario.room,
        &scenario.start,
        &mut SimRng::new(options.seed, Stream::Laser),
    );
    let scan = LaserScan {
        angle_min: f64::from(laser.angle_min() as f32),
        angle_increment: f64::from(laser.resolution as f32),
        range_min: f64::from(crate::sim::sensors::LASER_RANGE_MIN as f32),
        range_max: f64::from(laser.max_range as f32),
        ranges: &ranges,
    };
    let mut lines = Vec::new();
    LineExtractor::new(estimator.config.extraction)
        .and_then(|mut e| e.extract(&scan, &mut lines))
        .map_err(|e| ExperimentError::Setup(format!("first scan: {e}")))?;
    let map = LineMap::from_scan(&lines, &scenario.start.compose(&laser.mount))
        .map_err(|e| ExperimentError::Setup(format!("first-scan map: {e}")))?;
    scenario.path = loop_inside(&map, &scenario.start, CLEARANCE)?;
    estimator.map = Some(map.clone());
    let sim = simulate(
        &scenario,
        &SimOptions {
            seed: options.seed,
            feedback: Feedback::Estimate,
            estimator: Some(estimator),
        },
        None,
    )?;
    let errors: Vec<(f64, f64)> = sim
        .truth
        .iter()
        .zip(sim.estimate.iter())
        .map(|(t, e)| {
            (
                (e.pose.x - t.pose.x).hypot(e.pose.y - t.pose.y),
                angle_diff(e.pose.theta, t.pose.theta),
            )
        })
        .collect();
    let svg = options.out_dir.join("fig12.svg");
    super::write_svg(&svg, |w| draw(&map, &scenario.path, &sim, &errors, w))?;
    let report = Fig12Report {
        seed: options.seed,
        duration_s: scenario.steps() as f64 * scenario.dt,
        svg: svg.display().to_string(),
        map_segments: map.len(),
        clearance_m: CLEARANCE,
        lap_length_m: scenario.path.length(),
        distance_m: sim.stats.distance_m,
        rms_deviation_m: rms(sim.path_deviation.iter().copied()),
        max_deviation_m: sim.path_deviation.iter().copied().fold(0.0, f64::max),
        min_clearance_m: sim.stats.min_clearance_m,
        position_rmse_m: rms(errors.iter().map(|e| e.0)),
        heading_rmse_deg: rms(errors.iter().map(|e| e.1)).to_degrees(),
        lines_fused: sim.stats.lines_fused,
    };
    write_json(&options.out_dir.join("fig12.json"), &report)?;
    Ok(report)
}

/// A closed loop `clearance` inside the walls around `robot`: on each of the four sides
/// (normals 90° apart, aligned with the longest wall) the longest wall of at least 1 m
/// is moved towards the robot by `clearance`, and the loop runs through the corners
/// where neighbouring moved walls meet, counter-clockwise.
pub fn loop_inside(
    map: &LineMap,
    robot: &Pose2<f64>,
    clearance: f64,
) -> Result<Path, ExperimentError> {
    let r = Vector2::new(robot.x, robot.y);
    // Each wall as (outward normal angle seen from the robot, distance, length).
    let walls: Vec<(f64, f64, f64)> = map
        .segments
        .iter()
        .filter(|s| s.length() >= 1.0)
        .map(|s| {
            let n = Vector2::new(s.line.beta.cos(), s.line.beta.sin());
            let c = s.line.rho - n.dot(&r);
            let n = n * c.signum();
            (n.y.atan2(n.x), c.abs(), s.length())
        })
        .collect();
    let Some(&(phi0, _, _)) = walls.iter().max_by(|a, b| a.2.total_cmp(&b.2)) else {
        return Err(ExperimentError::Setup(
            "the first scan saw no wall of 1 m or more".into(),
        ));
    };
    let mut sides = Vec::with_capacity(4);
    for k in 0..4 {
        let axis = phi0 + f64::from(k) * std::f64::consts::FRAC_PI_2;
        let side = walls
            .iter()
            .filter(|w| angle_diff(w.0, axis).abs() < std::f64::consts::FRAC_PI_4)
            .max_by(|a, b| a.2.total_cmp(&b.2));
        match side {
            // The moved wall: points p with n·p = n·r + d − clearance.
            Some(&(phi, d, _)) => {
                let n = Vector2::new(phi.cos(), phi.sin());
                sides.push((n, n.dot(&r) + d - clearance));
            }
            None => {
                return Err(ExperimentError::Setup(format!(
                    "the first scan saw walls on only {} of the room's 4 sides",
                    k
                )))
            }
        }
    }
    let corners = (0..4)
        .map(|k| {
            let (a, b) = (sides[k], sides[(k + 1) % 4]);
            let m = Matrix2::new(a.0.x, a.0.y, b.0.x, b.0.y);
            m.try_inverse()
                .map(|inv| Point2::from(inv * Vector2::new(a.1, b.1)))
                .ok_or_else(|| ExperimentError::Setup("two sides are parallel".into()))
        })
        .collect::<Result<Vec<_>, _>>()?;
    Ok(Path::rounded_polygon(&corners, CORNER_RADIUS).map_err(crate::sim::ScenarioError::from)?)
}

fn draw<W: std::io::Write>(
    map: &LineMap,
    path: &Path,
    sim: &crate::sim::SimResult,
    errors: &[(f64, f64)],
    writer: W,
) -> Result<(), crate::plot::PlotError> {
    let walls: Vec<Wall> = crate::commands::figures::walls_of(&map.segments);
    let mut commanded = Trajectory::new();
    for (i, p) in path
        .points()
        .iter()
        .chain(path.points().first())
        .enumerate()
    {
        commanded.push(i as u64, Pose2::new(p.x, p.y, 0.0));
    }
    let estimates = [
        TrajectorySeries {
            name: "true trajectory",
            trajectory: &sim.truth,
        },
        TrajectorySeries {
            name: "EKF estimate",
            trajectory: &sim.estimate,
        },
    ];
    let stamps = sim.truth.iter().map(|p| p.t_ns);
    let position: Vec<(u64, f64)> = stamps.clone().zip(errors.iter().map(|e| e.0)).collect();
    let deviation: Vec<(u64, f64)> = stamps.zip(sim.path_deviation.iter().copied()).collect();
    let series = [
        TimeSeries {
            name: "EKF position error",
            points: &position,
        },
        TimeSeries {
            name: "true distance from the commanded loop",
            points: &deviation,
        },
    ];
    let panels = [
        Panel::Trajectories {
            title: "Walls of the first-scan map and the robot's trajectory",
            reference: Some(TrajectorySeries {
                name: "commanded loop",
                trajectory: &commanded,
            }),
            estimates: &estimates,
            walls: &walls,
            markers: &[],
        },
        Panel::ErrorsOverTime {
            title: "Errors over time",
            series: &series,
            y_desc: "[m]",
            markers: &[],
        },
    ];
    let options = PlotOptions {
        title: "Fig. 12: autonomous navigation round the first-scan map".into(),
        width: 1500,
        height: 650,
    };
    plot_figure(writer, &panels, 2, &options)
}
