//! An independent cross-check: a plain textbook EKF, written here from the equations with
//! arrays and no code from ekf-core, must give the same states and covariances over a
//! 1,000-step run with compass and line updates (to 1e-9).

use core::f64::consts::{FRAC_PI_2, PI};
use ekf_core::{Compass, DiffDrive, Ekf, LaserLine, Line, Pose2, WheelNoise, WheelSpeeds};
use nalgebra::{Matrix2, Matrix3};

type M = Vec<Vec<f64>>;

fn zeros(r: usize, c: usize) -> M {
    vec![vec![0.0; c]; r]
}
fn mul(a: &M, b: &M) -> M {
    let mut o = zeros(a.len(), b[0].len());
    for i in 0..a.len() {
        for j in 0..b[0].len() {
            o[i][j] = (0..b.len()).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    o
}
fn tr(a: &M) -> M {
    (0..a[0].len())
        .map(|j| a.iter().map(|r| r[j]).collect())
        .collect()
}
fn add(a: &M, b: &M) -> M {
    a.iter()
        .zip(b)
        .map(|(r, s)| r.iter().zip(s).map(|(x, y)| x + y).collect())
        .collect()
}
/// Gauss-Jordan inverse with partial pivoting.
fn inv(m: &M) -> M {
    let n = m.len();
    let mut a: M = m
        .iter()
        .enumerate()
        .map(|(i, r)| {
            r.iter()
                .copied()
                .chain((0..n).map(|j| f64::from(u8::from(i == j))))
                .collect()
        })
        .collect();
    for c in 0..n {
        let p = (c..n)
            .max_by(|&i, &j| a[i][c].abs().total_cmp(&a[j][c].abs()))
            .unwrap();
        a.swap(c, p);
        let pv = a[c][c];
        a[c].iter_mut().for_each(|v| *v /= pv);
        for r in 0..n {
            if r != c {
                let f = a[r][c];
                let row_c = a[c].clone();
                a[r].iter_mut().zip(row_c).for_each(|(v, w)| *v -= f * w);
            }
        }
    }
    a.into_iter().map(|r| r[n..].to_vec()).collect()
}
fn wrap(a: f64) -> f64 {
    let w = a - 2.0 * PI * ((a + PI) / (2.0 * PI)).floor();
    if w <= -PI {
        w + 2.0 * PI
    } else {
        w
    }
}

/// The textbook filter: state x (3×1), covariance P (3×3), and the robot's wheel radius,
/// track and wheel-noise parameters (δ, floor).
struct Textbook {
    x: [f64; 3],
    p: M,
    r: f64,
    l: f64,
    delta: f64,
    floor: f64,
}

impl Textbook {
    /// Eqs. 1–9 with the corrected W (third row ±Δt·R/L).
    fn predict(&mut self, wl: f64, wr: f64, dt: f64) {
        let (r, l, delta, floor) = (self.r, self.l, self.delta, self.floor);
        let ds = dt * r * (wl + wr) / 2.0;
        let dth = dt * r * (wr - wl) / l;
        let a = self.x[2] + dth / 2.0;
        let big_a = vec![
            vec![1.0, 0.0, -ds * a.sin()],
            vec![0.0, 1.0, ds * a.cos()],
            vec![0.0, 0.0, 1.0],
        ];
        let k = dt * r / 2.0;
        let w = vec![
            vec![
                k * (a.cos() - ds / l * a.sin()),
                k * (a.cos() + ds / l * a.sin()),
            ],
            vec![
                k * (a.sin() + ds / l * a.cos()),
                k * (a.sin() - ds / l * a.cos()),
            ],
            vec![dt * r / l, -dt * r / l],
        ];
        let q = vec![
            vec![delta * wr * wr + floor, 0.0],
            vec![0.0, delta * wl * wl + floor],
        ];
        self.p = add(
            &mul(&mul(&big_a, &self.p), &tr(&big_a)),
            &mul(&mul(&w, &q), &tr(&w)),
        );
        self.x = [
            self.x[0] + ds * a.cos(),
            self.x[1] + ds * a.sin(),
            wrap(self.x[2] + dth),
        ];
    }

    /// Eqs. 10–12 in the plain form P = (I − KH)P⁻, symmetrised.
    fn update(&mut self, y: &[f64], h: M, r: M) {
        let s = add(&mul(&mul(&h, &self.p), &tr(&h)), &r);
        let k = mul(&mul(&self.p, &tr(&h)), &inv(&s));
        for (xi, ki) in self.x.iter_mut().zip(&k) {
            *xi += ki.iter().zip(y).map(|(kij, yj)| kij * yj).sum::<f64>();
        }
        self.x[2] = wrap(self.x[2]);
        let kh = mul(&k, &h);
        let i_kh: M = (0..3)
            .map(|i| {
                (0..3)
                    .map(|j| f64::from(u8::from(i == j)) - kh[i][j])
                    .collect()
            })
            .collect();
        let p = mul(&i_kh, &self.p);
        self.p = (0..3)
            .map(|i| (0..3).map(|j| 0.5 * (p[i][j] + p[j][i])).collect())
            .collect();
    }

    fn update_compass(&mut self, phi: f64, var: f64) {
        self.update(
            &[wrap(phi - self.x[2])],
            vec![vec![0.0, 0.0, 1.0]],
            vec![vec![var]],
        );
    }

    /// Eqs. 17–18 for a laser at (mx, my, mθ) on the robot, derived here by the chain rule.
    fn update_line(&mut self, z: (f64, f64), cov: &M, rho: f64, beta: f64, mount: (f64, f64, f64)) {
        let (x, y, th) = (self.x[0], self.x[1], self.x[2]);
        let xs = x + th.cos() * mount.0 - th.sin() * mount.1;
        let ys = y + th.sin() * mount.0 + th.cos() * mount.1;
        let c = rho - xs * beta.cos() - ys * beta.sin();
        let sg = if c < 0.0 { -1.0 } else { 1.0 };
        let r_hat = c.abs();
        let psi_hat = wrap(beta - th - mount.2 + if c < 0.0 { PI } else { 0.0 });
        let dxs = -th.sin() * mount.0 - th.cos() * mount.1;
        let dys = th.cos() * mount.0 - th.sin() * mount.1;
        let h = vec![
            vec![
                -sg * beta.cos(),
                -sg * beta.sin(),
                -sg * (dxs * beta.cos() + dys * beta.sin()),
            ],
            vec![0.0, 0.0, -1.0],
        ];
        self.update(&[z.0 - r_hat, wrap(z.1 - psi_hat)], h, cov.clone());
    }
}

#[test]
fn agrees_with_a_textbook_ekf_over_1000_steps() {
    let (r, l, dt) = (0.05, 0.6, 0.1);
    let noise = WheelNoise::new(0.01, 1e-3).unwrap();
    let robot = DiffDrive::new(r, l).unwrap();
    let mount = (0.25, 0.05, -FRAC_PI_2);
    let mount_pose = Pose2::new(mount.0, mount.1, mount.2);
    // A 10 m × 6 m room: walls x = 0, x = 10, y = 0, y = 6 as (ρ, β).
    let walls = [
        (0.0_f64, PI),
        (10.0, 0.0),
        (0.0, -FRAC_PI_2),
        (6.0, FRAC_PI_2),
    ];
    let walls = walls.map(|(rho, beta)| {
        if rho == 0.0 {
            (1e-9, beta)
        } else {
            (rho, beta)
        }
    });
    let p0 = Matrix3::from_diagonal(&nalgebra::Vector3::new(0.02, 0.03, 0.01));
    let mut ekf = Ekf::new(Pose2::new(5.0, 1.5, 0.0), p0).unwrap();
    let mut book = Textbook {
        r,
        l,
        delta: noise.delta,
        floor: noise.floor,
        x: [5.0, 1.5, 0.0],
        p: vec![
            vec![0.02, 0.0, 0.0],
            vec![0.0, 0.03, 0.0],
            vec![0.0, 0.0, 0.01],
        ],
    };
    let line_cov = Matrix2::new(4e-4, 1e-5, 1e-5, 2e-4);
    let line_cov_m = vec![vec![4e-4, 1e-5], vec![1e-5, 2e-4]];

    for k in 0..1000 {
        let t = k as f64 * dt;
        // Circles of about 1.7 m radius around (5, 3.2), well inside the room.
        let (wl, wr) = (
            3.5 + 0.3 * (0.05 * t).sin(),
            5.0 + 0.3 * (0.05 * t + 1.0).cos(),
        );
        ekf.predict_wheels(&robot, &WheelSpeeds::new(wl, wr, dt).unwrap(), &noise)
            .unwrap();
        book.predict(wl, wr, dt);

        // A compass reading a little off the current estimate, in the map frame.
        let phi = wrap(book.x[2] + 0.02 * (1.3 * t).sin());
        ekf.update(&Compass::new(phi, 3e-4).unwrap(), None).unwrap();
        book.update_compass(phi, 3e-4);

        if k % 5 == 0 {
            for (j, &(rho, beta)) in walls.iter().enumerate().take(2 + (k / 5) % 3) {
                // A measurement near the predicted one (so the run stays in the room).
                let (xs, ys, ts) = {
                    let p = ekf.pose().compose(&mount_pose);
                    (p.x, p.y, p.theta)
                };
                let c = rho - xs * beta.cos() - ys * beta.sin();
                let z = (
                    c.abs() + 0.01 * (t + j as f64).sin(),
                    wrap(beta - ts + if c < 0.0 { PI } else { 0.0 } + 0.005 * (2.0 * t).cos()),
                );
                let m = LaserLine::new(
                    Line::new(z.0, z.1).unwrap(),
                    line_cov,
                    Line::new(rho, beta).unwrap(),
                    mount_pose,
                )
                .unwrap();
                ekf.update(&m, None).unwrap();
                book.update_line(z, &line_cov_m, rho, beta, mount);
            }
        }

        for i in 0..3 {
            let dx = if i == 2 {
                wrap(ekf.state()[i] - book.x[i])
            } else {
                ekf.state()[i] - book.x[i]
            };
            assert!(
                dx.abs() < 1e-9,
                "step {k}: x[{i}] {} vs {}",
                ekf.state()[i],
                book.x[i]
            );
            for j in 0..3 {
                let (a, b) = (ekf.covariance()[(i, j)], book.p[i][j]);
                assert!((a - b).abs() < 1e-9, "step {k}: P[{i}][{j}] {a} vs {b}");
            }
        }
    }
}
