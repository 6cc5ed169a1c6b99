//! The time-ordered localizer: measurements that arrive late, within the lag, are fused
//! exactly as if they had come on time; later ones are dropped and counted; the pose now
//! is what fusing the held readings gives.

use ekf_core::Pose2;
use ekf_fusion::{Fused, Fuser, FusionConfig, Input, Mode, TimedLocalizer};
use nalgebra::Matrix3;

const MS: u64 = 1_000_000;

/// A robot turning gently left: wheel angles every 20 ms and a heading every 100 ms (5 ms
/// after a wheel reading), for `seconds`. Returns `(stamp, input)` in stamp order.
fn drive(seconds: u64) -> Vec<(u64, Input)> {
    let (wl, wr) = (2.0, 2.2); // rad/s
    let (radius, track) = (0.05, 0.60);
    let mut inputs = Vec::new();
    for k in 0..=(seconds * 50) {
        let t = k * 20 * MS;
        let s = t as f64 * 1e-9;
        inputs.push((
            t,
            Input::WheelAngles {
                left: wl * s,
                right: wr * s,
                velocities: None,
            },
        ));
        if k % 5 == 0 && k > 0 {
            let ts = t + 5 * MS;
            let heading = radius * (wr - wl) / track * (ts as f64 * 1e-9);
            inputs.push((
                ts,
                Input::Heading {
                    heading,
                    variance: None,
                },
            ));
        }
    }
    inputs
}

fn localizer() -> TimedLocalizer<usize> {
    let config = FusionConfig {
        mode: Mode::Compass,
        ..FusionConfig::default()
    };
    let p0 = Matrix3::from_diagonal_element(1e-4);
    let fuser = Fuser::new(&config, Pose2::new(0.0, 0.0, 0.0), p0, 0, None).unwrap();
    TimedLocalizer::new(fuser, (config.max_lag * 1e9) as u64)
}

/// Pushes `(stamp, input)` in the order given (the arrival order) and fuses as it goes;
/// returns every fused step's (stamp, tag, pose, covariance) and the localizer.
type Fusions = Vec<(u64, usize, [f64; 3], Matrix3<f64>)>;

fn run(arrivals: &[(u64, Input)]) -> (Fusions, TimedLocalizer<usize>) {
    let mut loc = localizer();
    let mut out = Vec::new();
    let mut record = |loc: &TimedLocalizer<usize>, stamp, tag| {
        let f = loc.fuser().localizer();
        let p = f.pose();
        out.push((stamp, tag, [p.x, p.y, p.theta], *f.covariance()));
    };
    for (tag, (stamp, input)) in arrivals.iter().enumerate() {
        let _ = loc.push(*stamp, input.clone(), tag);
        while let Some(step) = loc.next_ready(&mut ()) {
            let step = step.unwrap();
            record(&loc, step.stamp_ns, step.tag);
        }
    }
    while let Some(step) = loc.next_held(&mut ()) {
        let step = step.unwrap();
        record(&loc, step.stamp_ns, step.tag);
    }
    (out, loc)
}

/// The arrival order when each heading comes `delay_ms` after its stamp.
fn with_late_headings(inputs: &[(u64, Input)], delay_ms: u64) -> Vec<(u64, Input)> {
    let mut arrivals: Vec<(u64, u64, Input)> = inputs
        .iter()
        .map(|(t, i)| {
            let arrival = if matches!(i, Input::Heading { .. }) {
                t + delay_ms * MS
            } else {
                *t
            };
            (arrival, *t, i.clone())
        })
        .collect();
    arrivals.sort_by_key(|a| a.0);
    arrivals.into_iter().map(|(_, t, i)| (t, i)).collect()
}

#[test]
fn headings_up_to_the_lag_late_give_the_estimate_they_give_on_time() {
    let inputs = drive(20);
    let (on_time, loc) = run(&inputs);
    let counts = loc.fuser().counts();
    assert!(counts.compass.accepted > 150, "{counts:?}");
    for delay in [100, 350, 480] {
        let (late, loc) = run(&with_late_headings(&inputs, delay));
        assert_eq!(loc.fuser().counts().too_late, 0);
        // The same inputs fused in the same (stamp) order: identical states, bit for bit.
        let strip = |f: &Fusions| -> Vec<_> { f.iter().map(|(s, _, p, c)| (*s, *p, *c)).collect() };
        assert_eq!(strip(&late), strip(&on_time), "delay {delay} ms");
    }
}

#[test]
fn a_heading_later_than_the_lag_is_dropped_counted_and_changes_nothing_else() {
    let inputs = drive(5);
    // The heading stamped 2.105 s arrives 600 ms late: after the wheel reading at 2.70 s
    // released everything stamped up to 2.20 s.
    let late_at = inputs
        .iter()
        .position(|(t, i)| *t == 2105 * MS && matches!(i, Input::Heading { .. }))
        .unwrap();
    let mut arrivals = inputs.clone();
    let late = arrivals.remove(late_at);
    let after = arrivals.iter().position(|(t, _)| *t > 2705 * MS).unwrap();
    arrivals.insert(after, late.clone());

    let mut loc = localizer();
    let mut refused = None;
    for (tag, (stamp, input)) in arrivals.iter().enumerate() {
        if let Err(e) = loc.push(*stamp, input.clone(), tag) {
            refused = Some(e);
        }
        while let Some(step) = loc.next_ready(&mut ()) {
            step.unwrap();
        }
    }
    while let Some(step) = loc.next_held(&mut ()) {
        step.unwrap();
    }
    let refused = refused.expect("the late heading is refused");
    assert_eq!((refused.stamp, refused.item.0), (late.0, late.1));
    assert!(refused.after > late.0);
    assert_eq!(loc.fuser().counts().too_late, 1);

    let without: Vec<_> = inputs
        .iter()
        .enumerate()
        .filter(|(k, _)| *k != late_at)
        .map(|(_, i)| i.clone())
        .collect();
    let (_, reference) = run(&without);
    assert_eq!(
        loc.fuser().localizer().ekf(),
        reference.fuser().localizer().ekf()
    );
}

#[test]
fn the_pose_now_is_the_state_fusing_the_held_readings_gives() {
    // Headings up to 3 s, then wheel readings only, so what is held at the end is motion.
    let inputs: Vec<_> = drive(4)
        .into_iter()
        .filter(|(t, i)| !matches!(i, Input::Heading { .. }) || *t < 3000 * MS)
        .collect();
    let mut loc = localizer();
    assert_eq!(loc.pose_now([]).unwrap(), None, "nothing fused yet");
    for (tag, (stamp, input)) in inputs.iter().enumerate() {
        loc.push(*stamp, input.clone(), tag).unwrap();
        while let Some(step) = loc.next_ready(&mut ()) {
            step.unwrap();
        }
    }
    assert_eq!(loc.held(), 25, "0.5 s of readings at 50 Hz are held");
    let fused_before = *loc.fuser().localizer().ekf();
    let now = loc.pose_now([]).unwrap().unwrap();
    assert_eq!(
        *loc.fuser().localizer().ekf(),
        fused_before,
        "the filter is left as it was"
    );
    assert_eq!(now.t_ns, 4000 * MS);
    assert_eq!(now.fused_ns, 3500 * MS);
    let mut kinds = Vec::new();
    while let Some(step) = loc.next_held(&mut ()) {
        kinds.push(step.unwrap().fused);
    }
    assert!(kinds
        .iter()
        .all(|f| *f == Fused::Motion { predicted: true }));
    let all = loc.fuser().localizer();
    assert_eq!(now.pose, all.pose());
    assert_eq!(now.covariance, *all.covariance());
    assert!(now.pose.theta > fused_before.pose().theta, "it turned");
}

#[test]
fn a_duplicated_heading_is_skipped_not_fused_twice() {
    let inputs = drive(1);
    let (_, once) = run(&inputs);
    let mut twice = inputs.clone();
    let at = twice
        .iter()
        .position(|(t, i)| *t == 505 * MS && matches!(i, Input::Heading { .. }))
        .unwrap();
    twice.insert(at + 1, twice[at].clone());
    let (_, loc) = run(&twice);
    assert_eq!(
        loc.fuser().localizer().ekf(),
        once.fuser().localizer().ekf(),
        "the copy changed the estimate"
    );
    assert_eq!(
        loc.fuser().counts().compass.accepted + loc.fuser().counts().compass.rejected,
        once.fuser().counts().compass.accepted + once.fuser().counts().compass.rejected
    );
}
