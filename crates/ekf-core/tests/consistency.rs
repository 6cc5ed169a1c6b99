//! Invariants over long random runs: `P` stays symmetric positive definite, every angle
//! the filter returns is wrapped, and a refused input leaves the state unchanged.

use core::f64::consts::PI;
use ekf_core::{
    ChiSquareGate, Compass, DiffDrive, Ekf, Error, LaserLine, Line, Motion, OdometryNoise, Pose2,
    Position, Real, WheelNoise, WheelSpeeds,
};
use nalgebra::{Cholesky, Matrix2, Matrix3};
use proptest::prelude::*;

/// One random filter input.
#[derive(Debug, Clone)]
enum Step {
    Wheels(f64, f64, f64),
    Odometry(f64, f64),
    Compass(f64, f64),
    Line(f64, f64, f64, f64, f64, f64),
    Position(f64, f64, f64),
}

fn step() -> impl Strategy<Value = Step> {
    prop_oneof![
        (-30.0..30.0, -30.0..30.0, 0.01..0.2).prop_map(|(l, r, dt)| Step::Wheels(l, r, dt)),
        (-1.0..1.0, -1.0..1.0).prop_map(|(ds, dth)| Step::Odometry(ds, dth)),
        (-PI..PI, 1e-6..1.0).prop_map(|(h, v)| Step::Compass(h, v)),
        // A wall anywhere, seen near where the filter predicts it: offsets dr, dψ of at most
        // half the line's own standard deviations, so yᵀR⁻¹y ≤ (0.25 + 0.25 + 2·0.9·0.25) /
        // (1 − 0.9²) < 5, and since S ≥ R the NIS is below the 0.99 gate (9.21): every
        // line update must be fused.
        (
            -0.5..0.5,
            -0.5..0.5,
            0.0..20.0,
            -PI..PI,
            1e-6..0.1,
            -0.9..0.9
        )
            .prop_map(|(dr, dpsi, rho, beta, var, corr)| Step::Line(
                dr, dpsi, rho, beta, var, corr
            )),
        (-50.0..50.0, -50.0..50.0, 1e-4..10.0).prop_map(|(x, y, v)| Step::Position(x, y, v)),
    ]
}

fn is_spd<T: Real>(p: &Matrix3<T>) -> bool {
    p.iter().all(|v| v.is_finite()) && *p == p.transpose() && Cholesky::new(*p).is_some()
}

fn wrapped<T: Real>(a: T) -> bool {
    a > -T::pi() && a <= T::pi()
}

/// Runs the steps through a filter over `T`, checking the invariants after each.
fn run<T: Real>(steps: &[Step]) -> Result<(), TestCaseError> {
    let c = T::lit;
    let robot = DiffDrive::new(c(0.05), c(0.6)).unwrap();
    let wheel_noise = WheelNoise::default();
    let odo_noise = OdometryNoise::default();
    let mount = Pose2::new(c(0.3), c(-0.05), c(-PI / 2.0));
    let line_gate = ChiSquareGate::from_probability(0.99, 2).unwrap();
    let compass_gate = ChiSquareGate::from_probability(0.99, 1).unwrap();
    let mut ekf = Ekf::new(
        Pose2::new(c(1.0), c(2.0), c(3.0)),
        Matrix3::from_diagonal_element(c(0.1)),
    )
    .unwrap();
    let (mut lines_fused, mut lines_tried) = (0usize, 0usize);
    for s in steps {
        let result = match *s {
            Step::Wheels(l, r, dt) => ekf
                .predict_wheels(
                    &robot,
                    &WheelSpeeds::new(c(l), c(r), c(dt)).unwrap(),
                    &wheel_noise,
                )
                .map(drop),
            Step::Odometry(ds, dth) => ekf
                .predict_odometry(&Motion::new(c(ds), c(dth)).unwrap(), &odo_noise)
                .map(drop),
            Step::Compass(h, v) => ekf
                .update(&Compass::new(c(h), c(v)).unwrap(), Some(&compass_gate))
                .map(|o| {
                    assert!(o.nis >= T::zero());
                }),
            Step::Line(dr, dpsi, rho, beta, var, corr) => {
                let cov = Matrix2::new(
                    c(var),
                    c(corr * var * 0.1),
                    c(corr * var * 0.1),
                    c(var * 0.01),
                );
                let wall = Line::new(c(rho), c(beta)).unwrap();
                let predicted = wall.to_frame(&ekf.pose().compose(&mount));
                if predicted.rho <= c(var.sqrt()) {
                    // The wall passes within 1σ of the laser: r̂ = |C| is not smooth there.
                    Ok(())
                } else {
                    lines_tried += 1;
                    let seen = Line::new(
                        predicted.rho + c(dr * var.sqrt()),
                        predicted.beta + c(dpsi * (var * 0.01).sqrt()),
                    )
                    .unwrap();
                    let m = LaserLine::new(seen, cov, wall, mount).unwrap();
                    ekf.update(&m, Some(&line_gate))
                        .map(|o| lines_fused += usize::from(o.accepted))
                }
            }
            Step::Position(x, y, v) => ekf
                .update(
                    &Position::new(c(x), c(y), Matrix2::from_diagonal_element(c(v))).unwrap(),
                    None,
                )
                .map(|_| ()),
        };
        prop_assert!(result.is_ok(), "step {:?} failed: {:?}", s, result);
        prop_assert!(
            is_spd(ekf.covariance()),
            "P not SPD after {:?}: {}",
            s,
            ekf.covariance()
        );
        prop_assert!(wrapped(ekf.pose().theta));
        prop_assert!(wrapped(ekf.state()[2]));
    }
    // The run really exercises line updates, not only gate rejections.
    prop_assert_eq!(lines_fused, lines_tried);
    let line_steps = steps.iter().filter(|s| matches!(s, Step::Line(..))).count();
    prop_assert!(
        lines_tried * 10 >= line_steps * 9,
        "{lines_tried} of {line_steps}"
    );
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(10))]

    /// 10 cases × 1,000 steps = 10,000 random predict/update steps per scalar type.
    #[test]
    fn covariance_stays_spd_f64(steps in prop::collection::vec(step(), 1000)) {
        run::<f64>(&steps)?;
    }

    #[test]
    fn covariance_stays_spd_f32(steps in prop::collection::vec(step(), 1000)) {
        run::<f32>(&steps)?;
    }
}

#[test]
fn refused_inputs_leave_the_state_unchanged() {
    let robot = DiffDrive::<f64>::paper();
    let mut ekf = Ekf::new(
        Pose2::new(1.0, 2.0, 0.5),
        Matrix3::from_diagonal_element(0.1),
    )
    .unwrap();
    let before = ekf;
    let nan_speed = WheelSpeeds {
        left: f64::NAN,
        right: 1.0,
        dt: 0.1,
    };
    assert_eq!(
        ekf.predict_wheels(&robot, &nan_speed, &WheelNoise::default()),
        Err(Error::NonFinite {
            what: "left wheel speed"
        })
    );
    assert_eq!(ekf, before);
    let bad_noise = WheelNoise {
        delta: f64::NAN,
        floor: 0.0,
    };
    assert!(ekf
        .predict_wheels(
            &robot,
            &WheelSpeeds::new(1.0, 1.0, 0.1).unwrap(),
            &bad_noise
        )
        .is_err());
    assert_eq!(ekf, before);
    let nan_motion = Motion {
        ds: f64::INFINITY,
        dtheta: 0.0,
    };
    assert!(ekf
        .predict_odometry(&nan_motion, &OdometryNoise::default())
        .is_err());
    assert_eq!(ekf, before);
    // A measurement whose fields were set directly, bypassing its constructor's checks.
    let negative = Compass {
        heading: 0.0,
        variance: -1.0,
    };
    assert_eq!(
        ekf.update(&negative, None),
        Err(Error::NotPositiveDefinite {
            what: "measurement noise"
        })
    );
    assert_eq!(ekf, before);
    let asym = LaserLine {
        observed: Line::new(1.0, 0.0).unwrap(),
        covariance: Matrix2::new(1.0, 0.2, 0.0, 1.0),
        map_line: Line::new(2.0, 0.0).unwrap(),
        mount: Pose2::identity(),
    };
    assert_eq!(
        ekf.update(&asym, None),
        Err(Error::NotSymmetric {
            what: "measurement noise"
        })
    );
    assert_eq!(ekf, before);
    let gate2 = ChiSquareGate::from_probability(0.99, 2).unwrap();
    assert!(
        ekf.update(&Compass::new(0.5, 0.01).unwrap(), Some(&gate2))
            .is_err(),
        "gate dof must match"
    );
    assert_eq!(ekf, before);
    // Negative or indefinite process noise (refused, state unchanged).
    let negative = Matrix3::from_diagonal(&nalgebra::Vector3::new(-1.0, 0.0, 0.0));
    assert_eq!(
        ekf.predict(&Motion::new(0.1, 0.0).unwrap(), &negative),
        Err(Error::NegativeVariance {
            what: "motion noise"
        })
    );
    let indefinite = Matrix3::new(1.0, 2.0, 0.0, 2.0, 1.0, 0.0, 0.0, 0.0, 1.0);
    assert_eq!(
        ekf.predict(&Motion::new(0.1, 0.0).unwrap(), &indefinite),
        Err(Error::NotPositiveDefinite {
            what: "motion noise"
        })
    );
    let singular = Matrix3::from_diagonal(&nalgebra::Vector3::new(1e-4, 0.0, 1e-6));
    let mut moved = ekf;
    assert!(
        moved
            .predict(&Motion::new(0.1, 0.0).unwrap(), &singular)
            .is_ok(),
        "a PSD, singular noise is valid"
    );
    let negative_delta = WheelNoise {
        delta: -10.0,
        floor: 0.0,
    };
    assert_eq!(
        ekf.predict_wheels(
            &robot,
            &WheelSpeeds::new(1.0, 1.0, 0.1).unwrap(),
            &negative_delta
        ),
        Err(Error::NegativeVariance {
            what: "wheel noise delta"
        })
    );
    let negative_odometry = OdometryNoise {
        a1: -0.1,
        ..OdometryNoise::default()
    };
    assert!(ekf
        .predict_odometry(&Motion::new(0.1, 0.0).unwrap(), &negative_odometry)
        .is_err());
    assert_eq!(ekf, before);
    // Invalid initial covariances.
    let not_pd = Matrix3::from_diagonal(&nalgebra::Vector3::new(1.0, -1.0, 1.0));
    assert_eq!(
        Ekf::new(Pose2::identity(), not_pd),
        Err(Error::NotPositiveDefinite {
            what: "initial covariance"
        })
    );
    let mut not_sym = Matrix3::identity();
    not_sym[(0, 1)] = 0.5;
    assert_eq!(
        Ekf::new(Pose2::identity(), not_sym),
        Err(Error::NotSymmetric {
            what: "initial covariance"
        })
    );
    assert!(Ekf::new(Pose2::new(f64::NAN, 0.0, 0.0), Matrix3::identity()).is_err());
}

#[test]
fn gate_rejects_an_outlier_and_keeps_the_state() {
    let mut ekf = Ekf::new(
        Pose2::new(0.0, 0.0, 0.0),
        Matrix3::from_diagonal_element(1e-4),
    )
    .unwrap();
    let before = ekf;
    let gate = ChiSquareGate::from_probability(0.99, 1).unwrap();
    // 90° off with σ_θ = 0.57° and σ_compass = 1.8°: NIS ≈ 2,300.
    let out = ekf
        .update(&Compass::new(PI / 2.0, 1e-3).unwrap(), Some(&gate))
        .unwrap();
    assert!(!out.accepted && out.nis > 2000.0);
    assert_eq!(ekf, before);
    let ok = ekf
        .update(&Compass::new(0.01, 1e-3).unwrap(), Some(&gate))
        .unwrap();
    assert!(ok.accepted);
    // NIS = y²/(P_θθ + R) = 1e-4 / 1.1e-3.
    assert!((ok.nis - 1e-4 / 1.1e-3).abs() < 1e-12);
}
