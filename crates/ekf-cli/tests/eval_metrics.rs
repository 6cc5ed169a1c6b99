//! APE, RPE, alignment and statistics against answers computed by hand.

use ekf_cli::eval::{
    ape, rpe, umeyama, AlignMode, AlignmentOptions, ApeOptions, EvalError, RpeOptions, Statistics,
};
use ekf_cli::trajectory::Trajectory;
use ekf_core::Pose2;
use nalgebra::Point2;
use std::f64::consts::PI;

const STEP_NS: u64 = 100_000_000;

/// A curved reference: 30 poses on an arc with varying speed (not collinear).
fn reference() -> Trajectory {
    let mut t = Trajectory::new();
    for k in 0..30 {
        let s = k as f64;
        t.push(
            k * STEP_NS,
            Pose2::new(2.0 + 0.5 * s, 1.0 + 0.02 * s * s, 0.04 * s - 1.0),
        );
    }
    t
}

/// `reference` with every pose mapped by `f`.
fn mapped(f: impl Fn(&Pose2<f64>) -> Pose2<f64>) -> Trajectory {
    reference()
        .iter()
        .map(|s| ekf_cli::trajectory::StampedPose::new(s.t_ns, f(&s.pose)))
        .collect()
}

fn with_mode(mode: AlignMode) -> ApeOptions {
    ApeOptions {
        alignment: AlignmentOptions {
            mode,
            n_to_align: None,
        },
        ..ApeOptions::default()
    }
}

/// Rotation by `a` about the origin, then translation by `(tx, ty)`, scale `s` first.
fn similarity(p: &Pose2<f64>, s: f64, a: f64, tx: f64, ty: f64) -> Pose2<f64> {
    let (sin, cos) = a.sin_cos();
    Pose2::new(
        s * (cos * p.x - sin * p.y) + tx,
        s * (sin * p.x + cos * p.y) + ty,
        p.theta + a,
    )
}

#[test]
fn statistics_of_one_to_four() {
    let s = Statistics::from_errors(&[4.0, 1.0, 3.0, 2.0]).unwrap();
    assert_eq!(s.sse, 30.0);
    assert_eq!(s.rmse, 7.5_f64.sqrt());
    assert_eq!(s.mean, 2.5);
    assert_eq!(s.median, 2.5);
    assert_eq!(s.std, 1.25_f64.sqrt());
    assert_eq!((s.min, s.max), (1.0, 4.0));
    assert_eq!(
        Statistics::from_errors(&[3.0, 1.0, 2.0]).unwrap().median,
        2.0
    );
    assert_eq!(Statistics::from_errors(&[]), Err(EvalError::NoErrors));
}

#[test]
fn constant_offset_gives_ape_half_metre_and_zero_rpe() {
    let estimate = mapped(|p| Pose2::new(p.x + 0.3, p.y + 0.4, p.theta));
    let result = ape(&reference(), &estimate, &ApeOptions::default()).unwrap();
    let s = result.summary.translation_m;
    for v in [s.rmse, s.mean, s.median, s.min, s.max] {
        assert!((v - 0.5).abs() < 1e-12, "{s:?}");
    }
    assert!(s.std < 1e-12);
    assert!((s.sse - 30.0 * 0.25).abs() < 1e-10);
    assert_eq!(result.summary.matched_poses, 30);
    assert_eq!(result.summary.alignment, None);
    assert!(result.summary.heading_error_deg.max < 1e-12);
    let e = result.errors[7];
    assert!((e.dx - 0.3).abs() < 1e-12 && (e.dy - 0.4).abs() < 1e-12);
    assert_eq!(e.t_ns, 7 * STEP_NS);

    let result = rpe(&reference(), &estimate, &RpeOptions::default()).unwrap();
    assert_eq!(result.summary.pairs, 29);
    assert!(result.summary.translation_m.max < 1e-12);
    assert!(result.summary.heading_error_deg.max < 1e-9);
}

#[test]
fn rotation_about_origin_is_undone_by_rigid_alignment() {
    let angle = 10_f64.to_radians();
    let estimate = mapped(|p| similarity(p, 1.0, angle, 0.0, 0.0));
    let plain = ape(&reference(), &estimate, &ApeOptions::default()).unwrap();
    assert!(plain.summary.translation_m.rmse > 0.5);
    assert!((plain.summary.heading_error_deg.max - 10.0).abs() < 1e-9);

    let aligned = ape(&reference(), &estimate, &with_mode(AlignMode::Rigid)).unwrap();
    assert!(
        aligned.summary.translation_m.max < 1e-9,
        "{:?}",
        aligned.summary
    );
    assert!(aligned.summary.heading_error_deg.max < 1e-9);
    let a = aligned.summary.alignment.unwrap();
    assert!((a.rotation_rad + angle).abs() < 1e-12);
    assert!(a.translation[0].abs() < 1e-9 && a.translation[1].abs() < 1e-9);
    assert_eq!(a.scale, 1.0);
}

#[test]
fn rigid_alignment_leaves_scale_and_similarity_alignment_removes_it() {
    let estimate = mapped(|p| similarity(p, 2.0, -0.7, 3.0, -1.5));
    let rigid = ape(&reference(), &estimate, &with_mode(AlignMode::Rigid)).unwrap();
    assert!(rigid.summary.translation_m.rmse > 1.0);
    assert!(rigid.summary.heading_error_deg.max < 1e-9);

    let sim = ape(
        &reference(),
        &estimate,
        &with_mode(AlignMode::RigidAndScale),
    )
    .unwrap();
    assert!(sim.summary.translation_m.max < 1e-9);
    let a = sim.summary.alignment.unwrap();
    assert!((a.scale - 0.5).abs() < 1e-12);
    assert!((a.rotation_rad - 0.7).abs() < 1e-12);
}

#[test]
fn scale_only_alignment_scales_about_the_origin() {
    let estimate = mapped(|p| similarity(p, 3.0, 0.0, 0.0, 0.0));
    let result = ape(&reference(), &estimate, &with_mode(AlignMode::ScaleOnly)).unwrap();
    let a = result.summary.alignment.unwrap();
    assert!((a.scale - 1.0 / 3.0).abs() < 1e-12);
    assert_eq!((a.rotation_rad, a.translation), (0.0, [0.0, 0.0]));
    assert!(result.summary.translation_m.max < 1e-9);
}

#[test]
fn origin_alignment_moves_first_pose_onto_reference() {
    // Any rigid motion of the whole trajectory is undone exactly.
    let estimate = mapped(|p| similarity(p, 1.0, 2.5, -4.0, 7.0));
    let result = ape(&reference(), &estimate, &with_mode(AlignMode::Origin)).unwrap();
    assert!(result.summary.translation_m.max < 1e-9);
    assert!(result.summary.heading_error_deg.max < 1e-9);
}

#[test]
fn alignment_on_the_first_poses_only() {
    // The first 10 poses are exact; the rest drift away. Aligning on the first 10 keeps
    // the estimate where it is; aligning on all of them would move it.
    let estimate = mapped(|p| {
        let drift = (p.x - 6.5).max(0.0);
        Pose2::new(p.x, p.y + 0.3 * drift, p.theta)
    });
    let first = ApeOptions {
        alignment: AlignmentOptions {
            mode: AlignMode::Rigid,
            n_to_align: Some(10),
        },
        ..ApeOptions::default()
    };
    let a = ape(&reference(), &estimate, &first).unwrap();
    let alignment = a.summary.alignment.unwrap();
    assert!(alignment.rotation_rad.abs() < 1e-12);
    assert!(a.errors[..10].iter().all(|e| e.translation < 1e-9));
    let all = ape(&reference(), &estimate, &with_mode(AlignMode::Rigid)).unwrap();
    assert!(all.summary.alignment.unwrap().rotation_rad.abs() > 1e-3);
}

#[test]
fn heading_errors_are_wrapped() {
    let mut reference = Trajectory::new();
    let mut estimate = Trajectory::new();
    reference.push(0, Pose2::new(0.0, 0.0, 179_f64.to_radians()));
    estimate.push(0, Pose2::new(0.0, 0.0, (-179_f64).to_radians()));
    let result = ape(&reference, &estimate, &ApeOptions::default()).unwrap();
    assert!((result.errors[0].heading_deg - 2.0).abs() < 1e-9);
    assert!((result.summary.heading_error_deg.rmse - 2.0).abs() < 1e-9);
}

#[test]
fn rpe_of_a_stretched_and_turning_estimate() {
    // Reference: straight along x, 1 m per frame. Estimate: 1.1 m per frame; every
    // relative motion is then 0.1 m too long. A heading that turns 1° per frame more
    // than the reference gives a 1° relative rotation error per frame (and a lateral
    // part, so only the angle is checked there).
    let mut reference = Trajectory::new();
    let mut stretched = Trajectory::new();
    let mut turning = Trajectory::new();
    for k in 0..10 {
        let s = k as f64;
        reference.push(k * STEP_NS, Pose2::new(s, 0.0, 0.0));
        stretched.push(k * STEP_NS, Pose2::new(1.1 * s, 0.0, 0.0));
        turning.push(k * STEP_NS, Pose2::new(s, 0.0, s.to_radians()));
    }
    let result = rpe(&reference, &stretched, &RpeOptions::default()).unwrap();
    let s = result.summary.translation_m;
    assert!(
        (s.min - 0.1).abs() < 1e-12 && (s.max - 0.1).abs() < 1e-12,
        "{s:?}"
    );
    assert_eq!((result.errors[0].i, result.errors[0].j), (0, 1));
    assert_eq!(result.errors[0].t_ns, STEP_NS);

    let result = rpe(&reference, &turning, &RpeOptions::default()).unwrap();
    let h = result.summary.heading_error_deg;
    assert!(
        (h.min - 1.0).abs() < 1e-9 && (h.max - 1.0).abs() < 1e-9,
        "{h:?}"
    );

    // Δ = 2: consecutive pairs (0,2) (2,4) (4,6) (6,8); all pairs (0,2) … (7,9).
    let delta2 = RpeOptions {
        delta_frames: 2,
        ..RpeOptions::default()
    };
    let result = rpe(&reference, &stretched, &delta2).unwrap();
    assert_eq!(result.summary.pairs, 4);
    assert!((result.summary.translation_m.rmse - 0.2).abs() < 1e-12);
    let all = RpeOptions {
        all_pairs: true,
        ..delta2
    };
    let result = rpe(&reference, &stretched, &all).unwrap();
    assert_eq!(result.summary.pairs, 8);
    assert_eq!((result.errors[7].i, result.errors[7].j), (7, 9));
}

#[test]
fn rpe_rejects_bad_steps() {
    let zero = RpeOptions {
        delta_frames: 0,
        ..RpeOptions::default()
    };
    assert_eq!(
        rpe(&reference(), &reference(), &zero).unwrap_err(),
        EvalError::InvalidDelta { delta: 0 }
    );
    let long = RpeOptions {
        delta_frames: 30,
        ..RpeOptions::default()
    };
    assert_eq!(
        rpe(&reference(), &reference(), &long).unwrap_err(),
        EvalError::NoPairs {
            delta: 30,
            poses: 30
        }
    );
}

#[test]
fn umeyama_closed_form_and_degenerate_input() {
    let reference: Vec<Point2<f64>> = reference()
        .iter()
        .map(|s| Point2::new(s.pose.x, s.pose.y))
        .collect();
    let estimate: Vec<Point2<f64>> = reference
        .iter()
        .map(|p| {
            let q = similarity(&Pose2::new(p.x, p.y, 0.0), 0.8, PI / 3.0, 1.0, 2.0);
            Point2::new(q.x, q.y)
        })
        .collect();
    let a = umeyama(&estimate, &reference, true).unwrap();
    assert!((a.scale - 1.25).abs() < 1e-12);
    assert!((a.rotation_rad + PI / 3.0).abs() < 1e-12);
    for (e, r) in estimate.iter().zip(&reference) {
        let p = a.apply(&Pose2::new(e.x, e.y, 0.0));
        assert!((p.x - r.x).abs() < 1e-9 && (p.y - r.y).abs() < 1e-9);
    }
    // Collinear points still have a unique planar rotation (evo refuses them).
    let line: Vec<Point2<f64>> = (0..5).map(|k| Point2::new(k as f64, 0.0)).collect();
    let turned: Vec<Point2<f64>> = (0..5).map(|k| Point2::new(0.0, k as f64)).collect();
    let a = umeyama(&line, &turned, false).unwrap();
    assert!((a.rotation_rad - PI / 2.0).abs() < 1e-12);

    let point = vec![Point2::new(1.0, 1.0); 5];
    assert_eq!(
        umeyama(&point, &reference[..5], false).unwrap_err(),
        EvalError::DegenerateAlignment { poses: 5 }
    );
    assert!(umeyama(&[], &[], false).is_err());
    let zero = ApeOptions {
        alignment: AlignmentOptions {
            mode: AlignMode::Rigid,
            n_to_align: Some(0),
        },
        ..ApeOptions::default()
    };
    assert_eq!(
        ape(&self::reference(), &self::reference(), &zero).unwrap_err(),
        EvalError::DegenerateAlignment { poses: 0 }
    );
}

#[test]
fn summary_serializes_with_evo_names() {
    let estimate = mapped(|p| Pose2::new(p.x + 0.3, p.y + 0.4, p.theta));
    let result = ape(&reference(), &estimate, &with_mode(AlignMode::Rigid)).unwrap();
    let json = serde_json::to_value(&result.summary).unwrap();
    assert_eq!(json["matched_poses"], 30);
    assert_eq!(json["reference_poses"], 30);
    assert_eq!(json["estimate_poses"], 30);
    for key in ["rmse", "mean", "median", "std", "min", "max", "sse"] {
        assert!(json["translation_m"][key].is_f64(), "{key}");
        assert!(json["heading_error_deg"][key].is_f64(), "{key}");
    }
    assert!(json["alignment"]["rotation_rad"].is_f64());
    assert!(json["alignment"]["translation"].is_array());
    assert_eq!(json["alignment"]["scale"], 1.0);

    let result = rpe(&reference(), &estimate, &RpeOptions::default()).unwrap();
    let json = serde_json::to_value(&result.summary).unwrap();
    assert_eq!(json["pairs"], 29);
    assert_eq!(json["delta_frames"], 1);
    assert_eq!(json["all_pairs"], false);
    assert!(json["alignment"].is_null());
}
