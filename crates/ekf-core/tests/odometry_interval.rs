//! Odometry noise over an interval does not depend on the message rate: however a stretch
//! of motion is cut into odometry messages, the variances added over it are those of one
//! step covering it.

use ekf_core::{Ekf, Motion, OdometryNoise, OdometryTravel, Pose2};
use nalgebra::Matrix3;
use proptest::prelude::*;

/// The noise of one step covering `steps` (their distances and turns added in absolute
/// value).
fn one_step(noise: &OdometryNoise<f64>, steps: &[(f64, f64)]) -> Matrix3<f64> {
    let (l, r) = steps.iter().fold((0.0_f64, 0.0_f64), |(l, r), (ds, dth)| {
        (l + ds.abs(), r + dth.abs())
    });
    noise.motion_covariance(&Motion::new(l, r).unwrap())
}

proptest! {
    #[test]
    fn increments_add_up_to_the_interval_noise(
        steps in prop::collection::vec((-0.5..0.5f64, -0.5..0.5f64), 1..40),
    ) {
        let noise = OdometryNoise::default();
        let mut travel = OdometryTravel::default();
        let mut sum = Matrix3::zeros();
        for (ds, dth) in &steps {
            let q = noise.interval_covariance(&mut travel, &Motion::new(*ds, *dth).unwrap());
            prop_assert!(q.iter().all(|v| *v >= 0.0), "{q}");
            sum += q;
        }
        let expected = one_step(&noise, &steps);
        prop_assert!((sum - expected).abs().max() <= 1e-12 * (1.0 + expected.abs().max()),
            "sum {sum} one step {expected}");
    }
}

#[test]
fn a_robot_at_rest_gains_nothing_and_a_reset_starts_over() {
    let noise = OdometryNoise::default();
    let mut travel = OdometryTravel::default();
    let rest = Motion::new(0.0, 0.0).unwrap();
    assert_eq!(
        noise.interval_covariance(&mut travel, &rest),
        Matrix3::zeros()
    );
    let step = Motion::new(0.3, 0.1).unwrap();
    let first = noise.interval_covariance(&mut travel, &step);
    assert_eq!(
        first,
        noise.motion_covariance(&step),
        "the first step: its own noise"
    );
    // The second step adds what takes the interval from 0.3 m to 0.6 m: the constant
    // term is not added again.
    let second = noise.interval_covariance(&mut travel, &step);
    let along = |l: f64| (noise.a1 * l + noise.b1).powi(2);
    assert!((second[(0, 0)] - (along(0.6) - along(0.3))).abs() < 1e-15);
    travel.reset();
    assert_eq!(noise.interval_covariance(&mut travel, &step), first);
}

#[test]
fn ten_messages_give_the_covariance_of_one() {
    // Straight motion along the heading, no heading noise: the state covariance after the
    // interval is exactly the one-step noise mapped by G, however it was delivered.
    let noise = OdometryNoise::<f64> {
        a3: 0.0,
        a4: 0.0,
        b3: 0.0,
        ..OdometryNoise::default()
    };
    // Next to no initial uncertainty (the filter needs a positive definite one).
    let start = Ekf::new(Pose2::new(1.0, 2.0, 0.7), Matrix3::identity() * 1e-12).unwrap();
    let mut one = start;
    one.predict_odometry_in(
        &Motion::new(1.0, 0.0).unwrap(),
        &noise,
        &mut OdometryTravel::default(),
    )
    .unwrap();
    let mut ten = start;
    let mut travel = OdometryTravel::default();
    for _ in 0..10 {
        ten.predict_odometry_in(&Motion::new(0.1, 0.0).unwrap(), &noise, &mut travel)
            .unwrap();
    }
    assert!((one.pose().x - ten.pose().x).abs() < 1e-12);
    let diff = (one.covariance() - ten.covariance()).abs().max();
    assert!(diff < 1e-12, "{} vs {}", one.covariance(), ten.covariance());
    // Message by message as independent steps, the proportional terms would give a tenth
    // of the variance along the motion, and the constant term ten times its share.
    let mut independent = start;
    for _ in 0..10 {
        independent
            .predict_odometry(&Motion::new(0.1, 0.0).unwrap(), &noise)
            .unwrap();
    }
    let along = |e: &Ekf<f64>| {
        let (c, s) = (0.7_f64.cos(), 0.7_f64.sin());
        let p = e.covariance();
        c * c * p[(0, 0)] + 2.0 * c * s * p[(0, 1)] + s * s * p[(1, 1)]
    };
    let expected_independent = 10.0 * (noise.a1 * 0.1 + noise.b1).powi(2);
    assert!((along(&independent) - expected_independent).abs() < 1e-10);
    assert!((along(&one) - (noise.a1 + noise.b1).powi(2)).abs() < 1e-10);
}
