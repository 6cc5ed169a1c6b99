//! Every Jacobian of the filter (A, W, G, H of each measurement) against central finite
//! differences of the model it linearises, at random states including θ near ±π, in f64;
//! and the f32 Jacobians against the f64 finite differences.

use core::f64::consts::PI;
use ekf_core::{
    angle_diff, Compass, DiffDrive, LaserLine, Line, Measurement, Motion, Pose2, Position,
    WheelSpeeds,
};
use nalgebra::{Matrix2, Matrix3, Matrix3x2, SMatrix, Vector3};
use proptest::prelude::*;

const H: f64 = 1e-6;
const TOL: f64 = 1e-6;

/// A difference of two states, with the heading wrapped.
fn state_diff(a: &Pose2<f64>, b: &Pose2<f64>) -> Vector3<f64> {
    Vector3::new(a.x - b.x, a.y - b.y, angle_diff(a.theta, b.theta))
}

/// Central differences of `f` (a pose-valued function of `n` parameters) at `u`.
fn numeric_jacobian<const N: usize>(
    u: [f64; N],
    f: impl Fn(&[f64; N]) -> Pose2<f64>,
) -> SMatrix<f64, 3, N> {
    let mut j = SMatrix::<f64, 3, N>::zeros();
    for k in 0..N {
        let (mut up, mut dn) = (u, u);
        up[k] += H;
        dn[k] -= H;
        j.set_column(k, &(state_diff(&f(&up), &f(&dn)) / (2.0 * H)));
    }
    j
}

/// Central differences of a measurement's `h` with respect to the pose.
fn numeric_h<const M: usize, Z: Measurement<f64, M>>(
    m: &Z,
    p: &Pose2<f64>,
    angle_rows: [bool; M],
) -> SMatrix<f64, M, 3> {
    let mut j = SMatrix::<f64, M, 3>::zeros();
    for k in 0..3 {
        let (mut up, mut dn) = (p.to_vector(), p.to_vector());
        up[k] += H;
        dn[k] -= H;
        let (zu, _) = m.predict(&Pose2::from_vector(&up));
        let (zd, _) = m.predict(&Pose2::from_vector(&dn));
        for i in 0..M {
            let d = if angle_rows[i] {
                angle_diff(zu[i], zd[i])
            } else {
                zu[i] - zd[i]
            };
            j[(i, k)] = d / (2.0 * H);
        }
    }
    j
}

fn close<const R: usize, const C: usize>(
    a: &SMatrix<f64, R, C>,
    b: &SMatrix<f64, R, C>,
    tol: f64,
) -> bool {
    (a - b).iter().all(|d| d.abs() <= tol)
}

/// Headings drawn uniformly, plus a band within 1e-3 of ±π where wrapping bites.
fn heading() -> impl Strategy<Value = f64> {
    prop_oneof![-PI..PI, (PI - 1e-3)..PI, -PI..(-PI + 1e-3)]
}

fn pose() -> impl Strategy<Value = Pose2<f64>> {
    (-20.0..20.0, -20.0..20.0, heading()).prop_map(|(x, y, t)| Pose2::new(x, y, t))
}

fn mount() -> impl Strategy<Value = Pose2<f64>> {
    (-0.8..0.8, -0.3..0.3, heading()).prop_map(|(x, y, t)| Pose2::new(x, y, t))
}

fn to_f32(p: &Pose2<f64>) -> Pose2<f32> {
    Pose2::new(p.x as f32, p.y as f32, p.theta as f32)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn state_jacobian_a(p in pose(), ds in -0.5..0.5, dth in -0.6..0.6) {
        let m = Motion::new(ds, dth).unwrap();
        let num = numeric_jacobian([p.x, p.y, p.theta], |u| m.apply(&Pose2::new(u[0], u[1], u[2])));
        prop_assert!(close(&m.state_jacobian(&p), &num, TOL), "A {} vs {}", m.state_jacobian(&p), num);
        let m32 = Motion::new(ds as f32, dth as f32).unwrap();
        let a32: Matrix3<f64> = m32.state_jacobian(&to_f32(&p)).cast();
        prop_assert!(close(&a32, &num, 1e-4));
    }

    #[test]
    fn input_jacobian_w(p in pose(), wl in -20.0..20.0, wr in -20.0..20.0, dt in 0.01..0.2,
                        r in 0.02..0.2, l in 0.2..1.0) {
        let robot = DiffDrive::new(r, l).unwrap();
        let f = |u: &[f64; 2]| robot.motion(&WheelSpeeds::new(u[1], u[0], dt).unwrap()).apply(&p);
        let num = numeric_jacobian([wr, wl], f); // columns (ω_R, ω_L)
        let w = robot.input_jacobian(&p, &WheelSpeeds::new(wl, wr, dt).unwrap());
        prop_assert!(close(&w, &num, TOL), "W {} vs {}", w, num);
        // Erratum 1: ∂θ/∂ω_R = Δt·R/L exactly.
        prop_assert!((w[(2, 0)] - dt * r / l).abs() < 1e-15);
        let robot32 = DiffDrive::new(r as f32, l as f32).unwrap();
        let w32: Matrix3x2<f64> = robot32.input_jacobian(&to_f32(&p), &WheelSpeeds::new(wl as f32, wr as f32, dt as f32).unwrap()).cast();
        prop_assert!(close(&w32, &num, 1e-4));
    }

    #[test]
    fn odometry_noise_jacobian_g(p in pose(), ds in -0.5..0.5, dth in -0.6..0.6) {
        // The model with a lateral displacement e perpendicular to the mid-angle heading.
        let f = |u: &[f64; 3]| {
            let mid = p.theta + u[2] / 2.0;
            Pose2::new(p.x + u[0] * mid.cos() - u[1] * mid.sin(), p.y + u[0] * mid.sin() + u[1] * mid.cos(), p.theta + u[2])
        };
        let num = numeric_jacobian([ds, 0.0, dth], f);
        let g = Motion::new(ds, dth).unwrap().noise_jacobian(&p);
        prop_assert!(close(&g, &num, TOL), "G {} vs {}", g, num);
    }

    #[test]
    fn line_jacobian_h(p in pose(), mnt in mount(), rho in 0.0..30.0, beta in -PI..PI) {
        let map_line = Line::new(rho, beta).unwrap();
        let m = LaserLine::new(Line::new(1.0, 0.0).unwrap(), Matrix2::identity(), map_line, mnt).unwrap();
        let (z, h) = m.predict(&p);
        // |C| is not differentiable where the line passes through the sensor.
        prop_assume!(z[0] > 1e-3);
        let num = numeric_h(&m, &p, [false, true]);
        prop_assert!(close(&h, &num, TOL), "H {} vs {}", h, num);
        prop_assert!(z[0] >= 0.0 && z[1] > -PI && z[1] <= PI);
        // Erratum 2: with the laser at the robot origin, ∂r/∂(x, y) = −sign(C)(cos β, sin β).
        let centred = LaserLine::new(m.observed, m.covariance, map_line, Pose2::identity()).unwrap();
        let (_, h0) = centred.predict(&p);
        let c = rho - p.x * beta.cos() - p.y * beta.sin();
        prop_assert!((h0[(0, 0)] + c.signum() * beta.cos()).abs() < 1e-12);
        prop_assert!((h0[(0, 1)] + c.signum() * beta.sin()).abs() < 1e-12);
        let m32 = LaserLine::new(Line::new(1.0f32, 0.0).unwrap(), Matrix2::identity(),
            Line::new(rho as f32, beta as f32).unwrap(), to_f32(&mnt)).unwrap();
        let (z32, h32) = m32.predict(&to_f32(&p));
        prop_assume!((z32[0] as f64 - z[0]).abs() < 1e-3); // same branch of |C| in f32
        let h32: SMatrix<f64, 2, 3> = h32.cast();
        prop_assert!(close(&h32, &num, 1e-4 * (1.0 + rho)));
    }

    #[test]
    fn line_map_jacobian(p in pose(), mnt in mount(), rho in 0.5..30.0, beta in -PI..PI) {
        let at = |rho: f64, beta: f64| {
            let map_line = Line::new(rho, beta).unwrap();
            LaserLine::new(Line::new(1.0, 0.0).unwrap(), Matrix2::identity(), map_line, mnt).unwrap()
        };
        let m = at(rho, beta);
        let (z, _) = m.predict(&p);
        prop_assume!(z[0] > 1e-3);
        let mut num = Matrix2::zeros();
        for (k, (dr, db)) in [(H, 0.0), (0.0, H)].into_iter().enumerate() {
            let (zu, _) = at(rho + dr, beta + db).predict(&p);
            let (zd, _) = at(rho - dr, beta - db).predict(&p);
            num[(0, k)] = (zu[0] - zd[0]) / (2.0 * H);
            num[(1, k)] = angle_diff(zu[1], zd[1]) / (2.0 * H);
        }
        let h_m = m.map_jacobian(&p);
        prop_assert!(close(&h_m, &num, TOL * (1.0 + rho)), "H_m {} vs {}", h_m, num);
    }

    #[test]
    fn compass_and_position_jacobians(p in pose(), hdg in -PI..PI) {
        let c = Compass::new(hdg, 1e-3).unwrap();
        let (z, h) = c.predict(&p);
        prop_assert!(close(&h, &numeric_h(&c, &p, [true]), TOL));
        prop_assert!(z[0] > -PI && z[0] <= PI);
        let g = Position::new(1.0, 2.0, Matrix2::identity()).unwrap();
        let (_, h) = g.predict(&p);
        prop_assert!(close(&h, &numeric_h(&g, &p, [false, false]), TOL));
    }
}
