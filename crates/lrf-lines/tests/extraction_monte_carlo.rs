//! Monte-Carlo check of the reported line covariance: over 300 noisy scans of one wall
//! (range noise σ_ρ = 30 mm, bearing noise σ_φ = 0.002 rad, the same values in the
//! simulation and in the parameters) the reported σ_r and σ_ψ are within 20 % of the
//! empirical spread of the estimates, and the reported r–ψ correlation matches the
//! empirical one in sign and size. Dropping the coupling, as ROS `laser_line_extraction`
//! does, would report σ_r far too small: checked too.

mod extraction_support;

use ekf_core::{angle_diff, Pose2};
use extraction_support::{simulate, Rng, Scanner, Wall};
use lrf_lines::{ExtractionParams, LineExtractor};
use nalgebra::Point2;

const SIGMA_RANGE: f64 = 0.03;
const SIGMA_BEARING: f64 = 0.002;
const SCANS: usize = 300;

#[test]
fn reported_covariance_matches_monte_carlo_spread() {
    // The wall x cos ψ + y sin ψ = r with r = 3, ψ = 0.4, seen from s = −0.5 to 3.0 along
    // it: off-centre from the foot of the normal, so r and ψ are strongly correlated.
    let (r_true, psi_true) = (3.0_f64, 0.4_f64);
    let (n, t) = (
        Point2::new(psi_true.cos(), psi_true.sin()),
        Point2::new(-psi_true.sin(), psi_true.cos()),
    );
    let at = |s: f64| Point2::new(r_true * n.x + s * t.x, r_true * n.y + s * t.y);
    let walls = [Wall {
        a: at(-0.5),
        b: at(3.0),
    }];
    let pose = Pose2::identity();
    let scanner = Scanner::new(180_f64.to_radians(), 0.5_f64.to_radians());
    let params = ExtractionParams {
        range_sigma: SIGMA_RANGE,
        bearing_sigma: SIGMA_BEARING,
        split_distance: 0.15,
        max_point_gap: 0.5,
        min_incidence: 10.0_f64.to_radians(),
        min_points: 8,
        min_length: 0.5,
        merge_probability: 0.99,
    };
    let mut extractor = LineExtractor::new(params).unwrap();
    let mut rng = Rng::new(2024);
    let mut lines = Vec::new();
    let (mut rs, mut psis) = (Vec::new(), Vec::new());
    let (mut var_r, mut var_psi, mut cov_rpsi, mut var_r_uncoupled) = (0.0, 0.0, 0.0, 0.0);
    for _ in 0..SCANS {
        let ranges = simulate(
            &walls,
            &pose,
            &scanner,
            SIGMA_RANGE,
            SIGMA_BEARING,
            &mut rng,
        );
        let scan = scanner.scan(&ranges);
        extractor.extract(&scan, &mut lines).unwrap();
        assert_eq!(lines.len(), 1, "{lines:#?}");
        let l = &lines[0];
        rs.push(l.line.rho - r_true);
        psis.push(angle_diff(l.line.beta, psi_true));
        let c = l.covariance;
        var_r += c[(0, 0)] / SCANS as f64;
        var_psi += c[(1, 1)] / SCANS as f64;
        cov_rpsi += c[(0, 1)] / SCANS as f64;
        // What dropping the r–ψ coupling reports: 1 / J_rr with J = Σ⁻¹.
        var_r_uncoupled += 1.0 / c.try_inverse().unwrap()[(0, 0)] / SCANS as f64;
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let (mr, mp) = (mean(&rs), mean(&psis));
    let emp_var_r = rs.iter().map(|x| (x - mr).powi(2)).sum::<f64>() / (SCANS - 1) as f64;
    let emp_var_psi = psis.iter().map(|x| (x - mp).powi(2)).sum::<f64>() / (SCANS - 1) as f64;
    let emp_cov = rs
        .iter()
        .zip(&psis)
        .map(|(a, b)| (a - mr) * (b - mp))
        .sum::<f64>()
        / (SCANS - 1) as f64;
    let (emp_sr, emp_sp) = (emp_var_r.sqrt(), emp_var_psi.sqrt());
    let (rep_sr, rep_sp) = (var_r.sqrt(), var_psi.sqrt());
    let emp_corr = emp_cov / (emp_sr * emp_sp);
    let rep_corr = cov_rpsi / (rep_sr * rep_sp);
    let report = format!(
        "σ_r reported {rep_sr:.5} empirical {emp_sr:.5}; σ_ψ reported {rep_sp:.6} empirical \
         {emp_sp:.6}; correlation reported {rep_corr:.3} empirical {emp_corr:.3}; σ_r without \
         coupling {:.5}",
        var_r_uncoupled.sqrt()
    );
    println!("{report}");
    assert!((rep_sr / emp_sr - 1.0).abs() <= 0.2, "{report}");
    assert!((rep_sp / emp_sp - 1.0).abs() <= 0.2, "{report}");
    assert!(rep_corr.signum() == emp_corr.signum(), "{report}");
    assert!((rep_corr - emp_corr).abs() <= 0.1, "{report}");
    // The estimate is unbiased to well within its spread.
    assert!(
        mr.abs() < 0.2 * emp_sr && mp.abs() < 0.2 * emp_sp,
        "bias {mr} {mp}; {report}"
    );
    // The coupling matters here: without it σ_r would be more than 1.3× too small.
    assert!(var_r_uncoupled.sqrt() * 1.3 < emp_sr, "{report}");
}
