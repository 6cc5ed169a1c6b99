//! One full predict + compass + two-line step with every number worked out by hand, in
//! exact rational arithmetic (`derivations/hand_step.py` reproduces them).

use core::f64::consts::FRAC_PI_2;
use ekf_core::{Compass, DiffDrive, Ekf, LaserLine, Line, Pose2, WheelNoise, WheelSpeeds};
use nalgebra::{Matrix2, Matrix3};

fn assert_close(got: f64, want: f64, what: &str) {
    assert!(
        (got - want).abs() < 1e-12,
        "{what}: got {got:e}, want {want:e}"
    );
}

#[test]
fn predict_compass_two_lines_by_hand() {
    // x₀ = (0, 0, 0), P₀ = 0.01·I.
    let mut ekf = Ekf::new(
        Pose2::new(0.0, 0.0, 0.0),
        Matrix3::from_diagonal_element(0.01),
    )
    .unwrap();

    // Predict: the paper's robot (R = 0.05, L = 0.6), ω_L = ω_R = 2 rad/s, Δt = 0.1 s, δ = 0.01.
    //   Δs = 0.1·0.05·2 = 0.01, Δθ = 0 → x⁻ = (0.01, 0, 0).
    //   A = [[1,0,0],[0,1,Δs],[0,0,1]]; Q = diag(0.04, 0.04);
    //   W = [[ΔtR/2, ΔtR/2], [ΔtR/2·Δs/L, −ΔtR/2·Δs/L], [ΔtR/L, −ΔtR/L]]
    //     = [[1/400, 1/400], [1/24000, −1/24000], [1/120, −1/120]].
    //   P⁻ = A P Aᵀ + W Q Wᵀ = [[20001/2000000, 0, 0],
    //                           [0, 72007201/7200000000, 3601/36000000],
    //                           [0, 3601/36000000, 1801/180000]].
    let robot = DiffDrive::paper();
    ekf.predict_wheels(
        &robot,
        &WheelSpeeds::new(2.0, 2.0, 0.1).unwrap(),
        &WheelNoise::paper(),
    )
    .unwrap();
    let p = ekf.covariance();
    assert_close(ekf.pose().x, 0.01, "x⁻");
    assert_close(p[(0, 0)], 20001.0 / 2_000_000.0, "P⁻xx");
    assert_close(p[(1, 1)], 72_007_201.0 / 7_200_000_000.0, "P⁻yy");
    assert_close(p[(1, 2)], 3601.0 / 36_000_000.0, "P⁻yθ");
    assert_close(p[(2, 2)], 1801.0 / 180_000.0, "P⁻θθ");
    assert_close(p[(0, 1)], 0.0, "P⁻xy");

    // Compass φ = 0.02 rad, R = 1e-4: y = 0.02, S = 1801/180000 + 1/10000 = 1819/180000,
    //   NIS = y²/S = 72/1819; x = (1/100, 3601/18190000, 1801/90950).
    let out = ekf
        .update(&Compass::new(0.02, 1e-4).unwrap(), None)
        .unwrap();
    assert!(out.accepted);
    assert_close(out.nis, 72.0 / 1819.0, "compass NIS");
    assert_close(ekf.pose().y, 3601.0 / 18_190_000.0, "y after compass");
    assert_close(ekf.pose().theta, 1801.0 / 90950.0, "θ after compass");

    // Line 1: the wall x = 2 (ρ = 2, β = 0), laser at the robot origin, seen at
    //   (r, ψ) = (1.985, −0.01) with R = [[1e-4, 2e-5], [2e-5, 4e-4]].
    //   r̂ = 2 − x, ψ̂ = −θ, H = [[−1, 0, 0], [0, 0, −1]]. NIS = 65176061119/333513513575.
    let mount = Pose2::identity();
    let cov1 = Matrix2::new(1e-4, 2e-5, 2e-5, 4e-4);
    let line1 = LaserLine::new(
        Line::new(1.985, -0.01).unwrap(),
        cov1,
        Line::new(2.0, 0.0).unwrap(),
        mount,
    )
    .unwrap();
    let out = ekf.update(&line1, None).unwrap();
    assert_close(out.nis, 65_176_061_119.0 / 333_513_513_575.0, "line 1 NIS");

    // Line 2: the wall y = 1.5 (ρ = 1.5, β = π/2), seen at (1.49, π/2 − 0.012),
    //   R = diag(2e-4, 1e-4); r̂ = 1.5 − y, ψ̂ = π/2 − θ, H = [[0, −1, 0], [0, 0, −1]].
    let cov2 = Matrix2::new(2e-4, 0.0, 0.0, 1e-4);
    let line2 = LaserLine::new(
        Line::new(1.49, FRAC_PI_2 - 0.012).unwrap(),
        cov2,
        Line::new(1.5, FRAC_PI_2).unwrap(),
        mount,
    )
    .unwrap();
    let out = ekf.update(&line2, None).unwrap();
    assert_close(
        out.nis,
        4_487_247_779_008_580_760_551.0 / 22_364_753_254_868_154_204_800.0,
        "line 2 NIS",
    );

    // The final state and covariance (exact fractions evaluated to f64).
    let want_x = [
        0.015211647188987995,
        0.009806913838012623,
        0.015264798330452009,
    ];
    let want_p = [
        [
            9.813801636130869e-05,
            4.2942641822774797e-10,
            2.1906829479266817e-06,
        ],
        [
            4.2942641822774797e-10,
            0.00019607843312614164,
            8.673550544255069e-09,
        ],
        [
            2.1906829479266817e-06,
            8.673550544255069e-09,
            4.424739249554626e-05,
        ],
    ];
    for (i, row) in want_p.iter().enumerate() {
        assert_close(ekf.state()[i], want_x[i], "x");
        for (j, want) in row.iter().enumerate() {
            assert_close(ekf.covariance()[(i, j)], *want, "P");
        }
    }
}

#[test]
fn process_noise_adds_to_the_covariance_and_leaves_the_state() {
    let p = Matrix3::new(4e-4, 1e-4, 0.0, 1e-4, 3e-4, 2e-5, 0.0, 2e-5, 1e-4);
    let mut ekf = Ekf::new(Pose2::new(1.0, 2.0, 0.5), p).unwrap();
    // Scaling P by λ = 3 is adding (λ − 1) P.
    ekf.add_process_noise(&(p * 2.0)).unwrap();
    assert_eq!(ekf.pose(), Pose2::new(1.0, 2.0, 0.5));
    assert!((ekf.covariance() - p * 3.0).abs().max() < 1e-18);
    // Not positive semi-definite, not symmetric, not finite: refused, P unchanged.
    let before = *ekf.covariance();
    let negative = Matrix3::from_diagonal_element(-1e-6);
    let asymmetric = Matrix3::new(1e-4, 1e-5, 0.0, 0.0, 1e-4, 0.0, 0.0, 0.0, 1e-4);
    let nan = Matrix3::from_diagonal_element(f64::NAN);
    // Small but indefinite: eigenvalues 2.01e-6, −1e-8 and 0.
    let small_indefinite = Matrix3::new(1e-6, 1.01e-6, 0.0, 1.01e-6, 1e-6, 0.0, 0.0, 0.0, 0.0);
    for q in [negative, asymmetric, nan, small_indefinite] {
        assert!(ekf.add_process_noise(&q).is_err(), "{q}");
        assert_eq!(*ekf.covariance(), before);
    }
    // Singular but PSD, however small: the zero matrix, and q v vᵀ at q = 1e-12.
    let v = nalgebra::Vector3::new(0.3, -1.7, 1.0);
    for q in [Matrix3::zeros(), v * v.transpose() * 1e-12] {
        assert!(ekf.add_process_noise(&q).is_ok(), "{q}");
    }
}
