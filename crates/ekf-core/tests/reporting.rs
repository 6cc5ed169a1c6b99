//! `Ekf::update_reporting` is `Ekf::update` bit for bit, and what it hands back is the
//! update's own `y = z − h(x)`, `S = H P Hᵀ + R` and `K = P Hᵀ S⁻¹` (eqs. 10–12).

use ekf_core::{
    ChiSquareGate, Compass, Considered, Ekf, LaserLine, Line, Measurement, Pose2, Position,
};
use nalgebra::{Matrix2, Matrix3, SMatrix};

const P: [f64; 9] = [4e-3, 1e-4, 2e-4, 1e-4, 3e-3, -1e-4, 2e-4, -1e-4, 1e-3];

/// Runs `m` through `update`, `update_reporting` and `update_considering` with nothing
/// considered from the same filter, checks that all three end in the same filter, and
/// checks `y`, `S` and `K` against the textbook formulas. Returns whether it was fused.
fn check<const M: usize, Z: Measurement<f64, M>>(m: &Z, gate: &ChiSquareGate<f64>) -> bool {
    let start = Ekf::new(Pose2::new(1.0, -0.5, 0.3), Matrix3::from_row_slice(&P)).unwrap();
    let (mut plain, mut reporting, mut none) = (start, start, start);
    let innovation = start.innovation(m).unwrap();
    let outcome = plain.update(m, Some(gate)).unwrap();
    let update = reporting.update_reporting(m, Some(gate)).unwrap();
    let schmidt = none
        .update_considering(m, &Considered::none(), Some(gate))
        .unwrap();
    assert_eq!(update.outcome, outcome);
    assert_eq!(reporting, plain);
    assert_eq!(update, schmidt);
    assert_eq!(none, plain);
    assert_eq!(update.innovation, innovation);

    // y = z − h(x) and S = H P Hᵀ + R at the state before the update.
    let pose = start.pose();
    let (z_hat, h) = m.predict(&pose);
    assert_eq!(update.innovation.y, m.residual(&m.measured(), &z_hat));
    let p = start.covariance();
    let s = h * p * h.transpose() + m.noise();
    assert!((update.innovation.s - s).amax() <= 1e-15 * s.amax());
    if outcome.accepted {
        // K = P Hᵀ S⁻¹ (eq. 10), and x⁺ = x⁻ + K y exactly as the filter computed it.
        let k: SMatrix<f64, 3, M> = p * h.transpose() * s.try_inverse().unwrap();
        assert!((update.gain - k).amax() <= 1e-12 * k.amax());
        let x = start.state() + update.gain * update.innovation.y;
        assert_eq!(reporting.pose(), Pose2::new(x[0], x[1], x[2]));
        assert_eq!(outcome.transition, Matrix3::identity() - update.gain * h);
    } else {
        // Refused: nothing applied, so K is zero and the filter unchanged.
        assert_eq!(update.gain, SMatrix::<f64, 3, M>::zeros());
        assert_eq!(reporting, start);
    }
    outcome.accepted
}

#[test]
fn reporting_is_the_plain_update_and_hands_back_its_y_s_and_k() {
    let gate1 = ChiSquareGate::from_probability(0.99, 1).unwrap();
    let gate2 = ChiSquareGate::from_probability(0.99, 2).unwrap();
    let near = Matrix2::new(1e-3, 2e-4, 2e-4, 2e-3);
    assert!(check(&Position::new(1.03, -0.52, near).unwrap(), &gate2));
    assert!(!check(
        &Position::new(3.0, 2.0, Matrix2::identity() * 1e-4).unwrap(),
        &gate2
    ));
    assert!(check(&Compass::new(0.32, 1e-3).unwrap(), &gate1));
    assert!(!check(&Compass::new(1.3, 1e-3).unwrap(), &gate1));
    // A wall seen 2 cm and 0.01 rad off (fused), and 0.5 m off (refused).
    let wall = Line::new(4.0, 0.7).unwrap();
    let mount = Pose2::new(0.3, -0.05, -core::f64::consts::FRAC_PI_2);
    let sensor = Pose2::new(1.0, -0.5, 0.3).compose(&mount);
    let seen = wall.to_frame(&sensor);
    let r = Matrix2::new(9e-4, 1e-5, 1e-5, 2e-4);
    for (dr, accepted) in [(0.02, true), (0.5, false)] {
        let observed = Line::new(seen.rho + dr, seen.beta - 0.01).unwrap();
        let line = LaserLine::new(observed, r, wall, mount).unwrap();
        assert_eq!(check(&line, &gate2), accepted);
    }
}
