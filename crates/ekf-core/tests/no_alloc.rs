//! A predict + update loop performs zero heap allocations (counted by a global allocator).

use ekf_core::{
    ChiSquareGate, Compass, DiffDrive, Ekf, LaserLine, Line, Motion, OdometryNoise, Pose2,
    WheelNoise, WheelSpeeds,
};
use nalgebra::{Matrix2, Matrix3};

mod alloc_support;

use alloc_support::allocations;

#[test]
fn predict_update_loop_does_not_allocate() {
    let robot = DiffDrive::<f64>::paper();
    let noise = WheelNoise::default();
    let odo = OdometryNoise::default();
    let gate1 = ChiSquareGate::from_probability(0.99, 1).unwrap();
    let gate2 = ChiSquareGate::from_probability(0.99, 2).unwrap();
    let wall = Line::new(3.0, 0.0).unwrap();
    let mount = Pose2::new(0.1, 0.0, -core::f64::consts::FRAC_PI_2);
    let mut ekf = Ekf::new(Pose2::identity(), Matrix3::from_diagonal_element(1e-3)).unwrap();

    let before = allocations();
    let mut accepted = 0;
    for k in 0..1000 {
        ekf.predict_wheels(&robot, &WheelSpeeds::new(1.0, 1.1, 0.1).unwrap(), &noise)
            .unwrap();
        ekf.predict_odometry(&Motion::new(0.001, 0.0).unwrap(), &odo)
            .unwrap();
        let c = Compass::new(ekf.pose().theta + 0.001 * f64::from(k % 3), 1e-3).unwrap();
        accepted += usize::from(ekf.update(&c, Some(&gate1)).unwrap().accepted);
        let observed = wall.to_frame(&ekf.pose().compose(&mount));
        let m =
            LaserLine::new(observed, Matrix2::from_diagonal_element(1e-4), wall, mount).unwrap();
        // The update that also hands back y, S and K allocates nothing either.
        let reported = ekf.update_reporting(&m, Some(&gate2)).unwrap();
        accepted += usize::from(reported.outcome.accepted);
    }
    let after = allocations();
    assert_eq!(
        after - before,
        0,
        "the filter allocated {} times",
        after - before
    );
    assert_eq!(accepted, 2000);
}
