//! The paper's robot (R = 5 cm, L = 60 cm, Δt = 0.1 s) drives two laps of a rounded
//! rectangle in a 6 m × 4 m walled room, estimated four ways as in the paper's Fig. 9:
//! odometry alone, EKF + compass, EKF + laser lines, EKF + laser lines + compass.
//!
//! The laser lines here are the room's walls seen from the true pose plus noise (known
//! association); the full pipeline with line extraction and matching lives in `lrf-lines`
//! and the `ekf` command. Run: `cargo run --release -p ekf-core --example paper_room`.

use core::f64::consts::{FRAC_PI_2, PI};
use ekf_core::{
    angle_diff, ChiSquareGate, Compass, DiffDrive, Ekf, LaserLine, Line, Pose2, WheelNoise,
    WheelSpeeds,
};
use nalgebra::{Matrix2, Matrix3};
use rand::{rngs::StdRng, SeedableRng};
use rand_distr::{Distribution, Normal};

const DT: f64 = 0.1;
/// Laser line noise (σ_r in m, σ_ψ in rad) and compass noise (rad).
const SIGMA_R: f64 = 0.01;
const SIGMA_PSI: f64 = 0.01;
const SIGMA_COMPASS: f64 = 0.02;

struct Estimator {
    name: &'static str,
    ekf: Ekf<f64>,
    compass: bool,
    laser: bool,
    sq_pos: f64,
    sq_heading: f64,
}

fn main() {
    let mut rng = StdRng::seed_from_u64(7);
    let robot = DiffDrive::paper();
    let noise = WheelNoise::<f64>::paper();
    let mount = Pose2::new(0.2, 0.0, -FRAC_PI_2); // a SICK with 0° to the right, 20 cm ahead
    let walls = [
        Line::new(3.0, 0.0),
        Line::new(3.0, PI),
        Line::new(2.0, FRAC_PI_2),
        Line::new(2.0, -FRAC_PI_2),
    ]
    .map(|l| l.unwrap());
    let line_cov = Matrix2::from_diagonal(&[SIGMA_R * SIGMA_R, SIGMA_PSI * SIGMA_PSI].into());
    let gate1 = ChiSquareGate::from_probability(0.99, 1).unwrap();
    let gate2 = ChiSquareGate::from_probability(0.99, 2).unwrap();
    let start = Pose2::new(-1.5, -1.0, 0.0);
    let p0 = Matrix3::from_diagonal(&[1e-4, 1e-4, 1e-4].into());
    let mut estimators = [
        ("odometry", false, false),
        ("EKF + compass", true, false),
        ("EKF + laser", false, true),
        ("EKF + laser + compass", true, true),
    ]
    .map(|(name, compass, laser)| Estimator {
        name,
        ekf: Ekf::new(start, p0).unwrap(),
        compass,
        laser,
        sq_pos: 0.0,
        sq_heading: 0.0,
    });

    let mut truth = start;
    let unit = Normal::new(0.0, 1.0).unwrap();
    // Rounded rectangle: straight 3 m, quarter turn of radius 0.5 m, straight 2 m, turn, …
    let (v, turn_rate) = (0.3, 0.3 / 0.5);
    let mut segments = Vec::new();
    for _ in 0..2 {
        for len in [3.0, 2.0, 3.0, 2.0] {
            segments.push((len / v, 0.0));
            segments.push((FRAC_PI_2 / turn_rate, turn_rate));
        }
    }
    let mut steps = 0usize;
    for (duration, w) in segments {
        for _ in 0..(duration / DT).round() as usize {
            // Commanded wheel speeds; the PID holds them to ±5 % (the paper), the encoders
            // measure what the wheels really did with the filter's noise model δω².
            let (wl_cmd, wr_cmd) = (
                (v - w * robot.track / 2.0) / robot.wheel_radius,
                (v + w * robot.track / 2.0) / robot.wheel_radius,
            );
            let (wl, wr) = (
                wl_cmd * (1.0 + 0.05 * (unit.sample(&mut rng) / 3.0)),
                wr_cmd * (1.0 + 0.05 * (unit.sample(&mut rng) / 3.0)),
            );
            truth = robot
                .motion(&WheelSpeeds::new(wl, wr, DT).unwrap())
                .apply(&truth);
            let sd = noise.delta.sqrt();
            let measured = WheelSpeeds::new(
                wl + sd * wl.abs() * unit.sample(&mut rng),
                wr + sd * wr.abs() * unit.sample(&mut rng),
                DT,
            )
            .unwrap();
            let heading = truth.theta + SIGMA_COMPASS * unit.sample(&mut rng);
            let sensor = truth.compose(&mount);
            let seen: Vec<(Line<f64>, Line<f64>)> = walls
                .iter()
                .map(|w| {
                    let l = w.to_frame(&sensor);
                    (
                        Line::new(
                            l.rho + SIGMA_R * unit.sample(&mut rng),
                            l.beta + SIGMA_PSI * unit.sample(&mut rng),
                        )
                        .unwrap(),
                        *w,
                    )
                })
                .collect();
            for e in estimators.iter_mut() {
                e.ekf.predict_wheels(&robot, &measured, &noise).unwrap();
                if e.compass {
                    e.ekf
                        .update(
                            &Compass::new(heading, SIGMA_COMPASS * SIGMA_COMPASS).unwrap(),
                            Some(&gate1),
                        )
                        .unwrap();
                }
                if e.laser && steps.is_multiple_of(2) {
                    for (observed, wall) in &seen {
                        let m = LaserLine::new(*observed, line_cov, *wall, mount).unwrap();
                        e.ekf.update(&m, Some(&gate2)).unwrap();
                    }
                }
                let p = e.ekf.pose();
                e.sq_pos += (p.x - truth.x).powi(2) + (p.y - truth.y).powi(2);
                e.sq_heading += angle_diff(p.theta, truth.theta).powi(2);
            }
            steps += 1;
        }
    }
    println!(
        "paper robot, two laps of a rounded rectangle in a 6 m × 4 m room, {steps} steps of {DT} s"
    );
    println!(
        "{:<24} {:>18} {:>18}",
        "estimator", "position RMSE (m)", "heading RMSE (°)"
    );
    for e in &estimators {
        let n = steps as f64;
        println!(
            "{:<24} {:>18.4} {:>18.3}",
            e.name,
            (e.sq_pos / n).sqrt(),
            (e.sq_heading / n).sqrt().to_degrees()
        );
    }
}
