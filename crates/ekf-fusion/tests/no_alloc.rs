//! Once warm, the time-ordered localizer allocates nothing: pushing wheel readings,
//! headings and scans (late ones among them), fusing them and asking for the pose now
//! make no heap allocation (counted by a global allocator). The inputs themselves are
//! made beforehand, as a driver that reuses its scan buffers would.

use ekf_core::Pose2;
use ekf_fusion::{Fused, Fuser, FusionConfig, Input, Scan, TimedLocalizer};
use nalgebra::Matrix3;

#[path = "../../ekf-core/tests/alloc_support/mod.rs"]
mod alloc_support;

use alloc_support::allocations;

const MS: u64 = 1_000_000;
const WHEEL_RADIUS: f64 = 0.05;
const TRACK: f64 = 0.60;

/// Range from `pose` along bearing `phi` (world) to the walls of a 10 m × 8 m room
/// centred on the origin.
fn range_to_walls(pose: &Pose2<f64>, phi: f64) -> f32 {
    let (dx, dy) = (phi.cos(), phi.sin());
    let mut best = f64::INFINITY;
    for (wall, along_x) in [(5.0, true), (-5.0, true), (4.0, false), (-4.0, false)] {
        let (d, p) = if along_x { (dx, pose.x) } else { (dy, pose.y) };
        if d.abs() > 1e-12 {
            let t = (wall - p) / d;
            if t > 0.0 {
                best = best.min(t);
            }
        }
    }
    best as f32
}

/// A robot driving a slow left arc from the room's centre: wheel angles at 50 Hz, a
/// heading at 10 Hz and a 181-beam scan at 10 Hz, the scans arriving 200 ms late.
/// Returns the inputs in arrival order.
fn inputs(seconds: u64) -> Vec<(u64, u64, Input)> {
    let (wl, wr) = (1.0, 1.05); // rad/s
    let (v, w) = (
        WHEEL_RADIUS * (wl + wr) / 2.0,
        WHEEL_RADIUS * (wr - wl) / TRACK,
    );
    let pose_at = |s: f64| {
        let theta = w * s;
        Pose2::new(v / w * theta.sin(), v / w * (1.0 - theta.cos()), theta)
    };
    let mut out = Vec::new();
    for k in 0..=(seconds * 50) {
        let t = k * 20 * MS;
        let s = t as f64 * 1e-9;
        let wheels = Input::WheelAngles {
            left: wl * s,
            right: wr * s,
            velocities: Some([wl, wr]),
        };
        out.push((t, t, wheels));
        if k % 5 == 0 {
            let pose = pose_at(s);
            let heading = Input::Heading {
                heading: pose.theta,
                variance: None,
            };
            out.push((t + MS, t + MS, heading));
            let angle_min = -core::f64::consts::FRAC_PI_2;
            let increment = core::f64::consts::PI / 180.0;
            let ranges = (0..181)
                .map(|i| range_to_walls(&pose, pose.theta + angle_min + i as f64 * increment))
                .collect();
            let scan = Scan {
                angle_min,
                angle_increment: increment,
                range_min: 0.05,
                range_max: 30.0,
                ranges,
            };
            out.push((t + 200 * MS, t, Input::Scan(scan)));
        }
    }
    out.sort_by_key(|(arrival, _, _)| *arrival);
    out
}

#[test]
fn once_warm_pushing_fusing_and_the_pose_now_do_not_allocate() {
    let config = FusionConfig::default();
    let p0 = Matrix3::from_diagonal_element(1e-4);
    let fuser = Fuser::new(&config, Pose2::new(0.0, 0.0, 0.0), p0, 0, None).unwrap();
    let mut loc: TimedLocalizer<()> = TimedLocalizer::new(fuser, 500 * MS);
    let all = inputs(20);
    let warm = all
        .iter()
        .position(|(arrival, _, _)| *arrival > 5_000 * MS)
        .unwrap();
    // Fuses what is ready; returns the lines fused.
    let fused = |loc: &mut TimedLocalizer<()>| {
        let mut lines = 0;
        while let Some(step) = loc.next_ready(&mut ()) {
            if let Fused::Scan(s) = step.unwrap().fused {
                lines += s.report.fused;
            }
        }
        lines
    };
    let mut fused_lines = 0;
    let mut rest = all.into_iter();
    for (_, stamp, input) in rest.by_ref().take(warm) {
        loc.push(stamp, input, ()).unwrap();
        fused_lines += fused(&mut loc);
    }
    let warm_lines = fused_lines;
    let before = allocations();
    let mut predicted_ahead = 0;
    for (_, stamp, input) in rest {
        loc.push(stamp, input, ()).unwrap();
        fused_lines += fused(&mut loc);
        let now = loc.pose_now([]).unwrap().unwrap();
        predicted_ahead += usize::from(now.t_ns > now.fused_ns);
    }
    let allocations = allocations() - before;
    assert_eq!(allocations, 0, "allocations after warm-up");
    assert!(
        warm_lines > 0 && fused_lines > warm_lines + 200,
        "{fused_lines} lines fused"
    );
    assert!(
        predicted_ahead > 500,
        "the pose now ran ahead {predicted_ahead} times"
    );
    assert_eq!(loc.fuser().counts().too_late, 0);
}
