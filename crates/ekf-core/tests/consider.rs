//! The Schmidt–Kalman (consider) update against the Kalman update of the state augmented
//! with the considered parameters, at random states, covariances and map lines.

use ekf_core::{ChiSquareGate, Considered, Ekf, LaserLine, Line, Measurement, Pose2, Position};
use nalgebra::{Matrix2, Matrix3, Matrix3x2, SMatrix, Vector3};
use proptest::prelude::*;

type Matrix5 = SMatrix<f64, 5, 5>;

/// A random symmetric positive definite `N × N` matrix: `L Lᵀ + ε I` with `L` from
/// `entries` scaled by `scale`.
fn spd<const N: usize>(entries: &[f64], scale: f64) -> SMatrix<f64, N, N> {
    let l = SMatrix::<f64, N, N>::from_iterator(entries.iter().map(|e| e * scale));
    l * l.transpose() + SMatrix::identity() * (1e-4 * scale * scale)
}

fn covariance_5() -> impl Strategy<Value = Matrix5> {
    prop::collection::vec(-1.0..1.0, 25).prop_map(|e| {
        // Pose errors of a few cm and degrees, map errors of a few cm and degrees.
        let scale = SMatrix::<f64, 5, 5>::from_diagonal(&[0.05, 0.05, 0.03, 0.04, 0.02].into());
        scale * spd::<5>(&e, 1.0) * scale
    })
}

fn line_at(pose: &Pose2<f64>, rho: f64, beta: f64) -> LaserLine<f64> {
    let map_line = Line::new(rho, beta).unwrap();
    let mount = Pose2::new(0.3, -0.05, -core::f64::consts::FRAC_PI_2);
    let truth = LaserLine::new(
        Line::new(1.0, 0.0).unwrap(),
        Matrix2::identity(),
        map_line,
        mount,
    )
    .unwrap();
    let (z, _) = truth.predict(pose);
    // Observed a little off the prediction, with the paper's laser noise.
    let observed = Line::new(z[0] + 0.02, z[1] - 0.01).unwrap();
    let r = Matrix2::new(9e-4, 1e-5, 1e-5, 2e-4);
    LaserLine::new(observed, r, map_line, mount).unwrap()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn consider_update_is_the_augmented_update_with_the_parameters_held(
        x in -3.0..3.0, y in -3.0..3.0, theta in -3.1..3.1,
        rho in 4.0..8.0, beta in -3.1..3.1,
        p5 in covariance_5(),
    ) {
        let pose = Pose2::new(x, y, theta);
        let m = line_at(&pose, rho, beta);
        let p: Matrix3<f64> = p5.fixed_view::<3, 3>(0, 0).into();
        let cross: Matrix3x2<f64> = p5.fixed_view::<3, 2>(0, 3).into();
        let c: Matrix2<f64> = p5.fixed_view::<2, 2>(3, 3).into();
        let considered = Considered { jacobian: m.map_jacobian(&pose), cross, covariance: c };
        let mut ekf = Ekf::new(pose, p).unwrap();
        let update = ekf.update_considering(&m, &considered, None).unwrap();

        // The augmented state (x, y, θ, ρ, β): H_a = [H  H_m].
        let (z_hat, h) = m.predict(&pose);
        let y_inn = m.residual(&m.measured(), &z_hat);
        let mut h_a = SMatrix::<f64, 2, 5>::zeros();
        h_a.fixed_view_mut::<2, 3>(0, 0).copy_from(&h);
        h_a.fixed_view_mut::<2, 2>(0, 3).copy_from(&considered.jacobian);
        let s = h_a * p5 * h_a.transpose() + m.noise();
        let k_opt = p5 * h_a.transpose() * s.try_inverse().unwrap();
        // Schmidt: the state rows of the optimal gain, the parameters' rows zero.
        let mut k_a = k_opt;
        k_a.fixed_view_mut::<2, 2>(3, 0).fill(0.0);
        let i_kh = Matrix5::identity() - k_a * h_a;
        let p_a = i_kh * p5 * i_kh.transpose() + k_a * m.noise() * k_a.transpose();
        let x_a = Vector3::new(x, y, theta) + k_a.fixed_view::<3, 2>(0, 0) * y_inn;

        let tol = 1e-10;
        prop_assert!((update.gain - k_a.fixed_view::<3, 2>(0, 0)).amax() < tol);
        prop_assert!((ekf.state() - x_a).amax() < tol);
        let p_x: Matrix3<f64> = p_a.fixed_view::<3, 3>(0, 0).into();
        prop_assert!((ekf.covariance() - p_x).amax() < tol, "{} vs {}", ekf.covariance(), p_x);
        // The state block is also the optimal one: holding the parameters loses nothing
        // for the state at this step.
        let i_kh_opt = Matrix5::identity() - k_opt * h_a;
        let p_opt = i_kh_opt * p5 * i_kh_opt.transpose() + k_opt * m.noise() * k_opt.transpose();
        prop_assert!((ekf.covariance() - p_opt.fixed_view::<3, 3>(0, 0)).amax() < tol);
        // The cross-covariance after the update.
        let cross_after = update.cross_after(&cross, &(considered.jacobian * c));
        prop_assert!((cross_after - p_a.fixed_view::<3, 2>(0, 3)).amax() < tol);
        // The covariance stays symmetric positive definite.
        let q = ekf.covariance();
        prop_assert!((q - q.transpose()).amax() == 0.0);
        prop_assert!(q.cholesky().is_some());
    }
}

#[test]
fn with_nothing_considered_it_is_the_plain_update_bit_for_bit() {
    let pose = Pose2::new(1.0, -0.5, 0.3);
    let p = Matrix3::new(4e-3, 1e-4, 2e-4, 1e-4, 3e-3, -1e-4, 2e-4, -1e-4, 1e-3);
    let m = line_at(&pose, 5.0, 0.7);
    let gate = ChiSquareGate::from_probability(0.99, 2).unwrap();
    let nothing = Considered {
        jacobian: m.map_jacobian(&pose),
        cross: Matrix3x2::zeros(),
        covariance: Matrix2::zeros(),
    };
    let (mut plain, mut schmidt) = (Ekf::new(pose, p).unwrap(), Ekf::new(pose, p).unwrap());
    let a = plain.update(&m, Some(&gate)).unwrap();
    let b = schmidt
        .update_considering(&m, &nothing, Some(&gate))
        .unwrap();
    assert!(a.accepted);
    assert_eq!(a, b.outcome);
    assert_eq!(plain, schmidt);
    assert_eq!(
        a.transition,
        Matrix3::identity() - b.gain * m.predict(&pose).1
    );
}

#[test]
fn considering_none_is_the_plain_update_and_hands_back_its_innovation() {
    let pose = Pose2::new(1.0, -0.5, 0.3);
    let p = Matrix3::new(4e-3, 1e-4, 2e-4, 1e-4, 3e-3, -1e-4, 2e-4, -1e-4, 1e-3);
    let gate = ChiSquareGate::from_probability(0.99, 2).unwrap();
    for (m, accepted) in [
        (
            Position::new(1.03, -0.52, Matrix2::new(1e-3, 2e-4, 2e-4, 2e-3)).unwrap(),
            true,
        ),
        // Far outside the gate: rejected by both, nothing changed.
        (
            Position::new(3.0, 2.0, Matrix2::identity() * 1e-4).unwrap(),
            false,
        ),
    ] {
        let (mut plain, mut none) = (Ekf::new(pose, p).unwrap(), Ekf::new(pose, p).unwrap());
        let innovation = plain.innovation(&m).unwrap();
        let a = plain.update(&m, Some(&gate)).unwrap();
        let b = none
            .update_considering(&m, &Considered::none(), Some(&gate))
            .unwrap();
        assert_eq!(a.accepted, accepted);
        assert_eq!(a, b.outcome);
        assert_eq!(plain, none);
        assert_eq!(innovation, b.innovation);
    }
}

#[test]
fn a_rejected_measurement_changes_nothing_and_its_transition_is_the_identity() {
    let pose = Pose2::new(0.0, 0.0, 0.0);
    let mut ekf = Ekf::new(pose, Matrix3::identity() * 1e-4).unwrap();
    let far = Position::new(5.0, 5.0, Matrix2::identity() * 1e-4).unwrap();
    let gate = ChiSquareGate::from_probability(0.99, 2).unwrap();
    let before = ekf;
    let outcome = ekf.update(&far, Some(&gate)).unwrap();
    assert!(!outcome.accepted);
    assert_eq!(outcome.transition, Matrix3::identity());
    assert_eq!(ekf, before);
}

#[test]
fn invalid_considered_covariances_are_refused() {
    let pose = Pose2::new(1.0, -0.5, 0.3);
    let m = line_at(&pose, 5.0, 0.7);
    let mut ekf = Ekf::new(pose, Matrix3::identity() * 1e-3).unwrap();
    let negative = Considered {
        jacobian: m.map_jacobian(&pose),
        cross: Matrix3x2::zeros(),
        covariance: Matrix2::new(-1e-3, 0.0, 0.0, 1e-3),
    };
    assert_eq!(
        ekf.update_considering(&m, &negative, None),
        Err(ekf_core::Error::NegativeVariance {
            what: "considered parameters' covariance"
        })
    );
    let nan = Considered {
        cross: Matrix3x2::from_element(f64::NAN),
        ..negative
    };
    assert!(ekf.update_considering(&m, &nan, None).is_err());
}
