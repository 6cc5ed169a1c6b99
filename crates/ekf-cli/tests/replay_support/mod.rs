//! Synthetic ROS 2 bags for the `ekf replay` tests: a differential-drive robot driving
//! loops in a rectangular room, with wheel joint states (or odometry), ray-cast laser
//! scans, an `Imu` compass, a ground truth and `/tf_static`. Everything is generated at
//! test time from a fixed seed and written to a temporary directory.
//!
//! A bag is first built as a list of [`Item`]s (log time, topic, message) so a test can
//! damage, drop or add messages before [`write_bag`] writes them.

#![allow(dead_code)] // each test file uses a different part

#[path = "../ekf_bin/mod.rs"]
mod ekf_bin;
#[path = "../gauss_rng/mod.rs"]
mod gauss_rng;

use ekf_cli::mcap_io::{BagReader, BagWriter};
use ekf_cli::ros2::build::{self, header};
use ekf_cli::ros2::geometry_msgs::{Quaternion, Transform, TransformStamped, Vector3};
use ekf_cli::ros2::nav_msgs::Odometry;
use ekf_cli::ros2::sensor_msgs::{Imu, JointState, LaserScan};
use ekf_cli::ros2::tf2_msgs::TFMessage;
use ekf_cli::ros2::AnyMessage;
pub use gauss_rng::Rng;
use std::collections::BTreeMap;
use std::f64::consts::{FRAC_PI_2, PI};
use std::path::{Path, PathBuf};
use std::process::Output;

/// First stamp: a realistic epoch time with nanoseconds that an `f64` would not keep.
pub const T0_NS: u64 = 1_700_000_000_123_456_789;
/// Motion period (10 Hz).
pub const DT_NS: u64 = 100_000_000;
/// Wheel radius and track of the simulated robot (the configuration's defaults).
pub const WHEEL_RADIUS: f64 = 0.05;
/// Distance between the wheels.
pub const TRACK: f64 = 0.6;
/// The room: x in [ROOM_X0, ROOM_X1], y in [ROOM_Y0, ROOM_Y1].
pub const ROOM_X0: f64 = -1.5;
/// See [`ROOM_X0`].
pub const ROOM_X1: f64 = 4.5;
/// See [`ROOM_X0`].
pub const ROOM_Y0: f64 = -2.0;
/// See [`ROOM_X0`].
pub const ROOM_Y1: f64 = 2.0;
/// Topic of the filler messages (ignored by the replay).
pub const FILLER_TOPIC: &str = "/lidar3d/scan";
/// Beams per scan (1° apart over a full turn; the last repeats the first direction).
pub const BEAMS: usize = 361;

/// A planar pose.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct P2 {
    pub x: f64,
    pub y: f64,
    pub theta: f64,
}

impl P2 {
    fn compose(&self, other: &P2) -> P2 {
        let (s, c) = self.theta.sin_cos();
        P2 {
            x: self.x + c * other.x - s * other.y,
            y: self.y + s * other.x + c * other.y,
            theta: self.theta + other.theta,
        }
    }
}

/// Which motion topic the bag carries.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MotionTopic {
    /// `/joint_states` (JointState with positions and velocities).
    Joints,
    /// `/odom` (Odometry, dead-reckoned from the scaled wheels).
    Odom,
    /// Neither.
    None,
}

/// What to put in a bag.
#[derive(Debug, Clone)]
pub struct Scenario {
    /// Loops around the rectangle.
    pub loops: usize,
    /// Stop after this many motion periods (`None`: the whole drive).
    pub max_steps: Option<usize>,
    /// Motion topic.
    pub motion: MotionTopic,
    /// Scale errors of the recorded left and right wheel angles (1.0 = exact).
    pub wheel_scale: (f64, f64),
    /// Standard deviation of a white noise on the recorded wheel speeds (rad/s), per
    /// motion period: encoder quantisation and slip.
    pub wheel_noise: f64,
    /// Joint names in the joint states.
    pub joint_names: (String, String),
    /// A scan every this many motion periods (0: no scans), at [`scan_stamp`].
    pub scan_every: usize,
    /// Range noise (m).
    pub range_sigma: f64,
    /// Field of view of the laser (rad): [`BEAMS`] beams evenly over it, centred ahead.
    pub fov: f64,
    /// Largest range the laser returns (m); farther walls read +inf (REP 117: no return).
    pub range_max: f64,
    /// A compass reading every this many motion periods (0: none), at [`compass_stamp`].
    pub compass_every: usize,
    /// Compass noise (rad).
    pub compass_sigma: f64,
    /// Ground truth at every motion stamp and scan stamp.
    pub ground_truth: bool,
    /// `/tf_static` with base_link → laser.
    pub tf_static: bool,
    /// The laser's mounting pose on the robot.
    pub mount: P2,
    /// A filler scan on [`FILLER_TOPIC`] (random, incompressible) of this size every second, to make
    /// the bag span several MCAP chunks; 0: none.
    pub filler_bytes: usize,
    /// Noise seed.
    pub seed: u64,
}

impl Default for Scenario {
    fn default() -> Self {
        Self {
            loops: 2,
            max_steps: None,
            motion: MotionTopic::Joints,
            wheel_scale: (1.02, 1.03),
            wheel_noise: 0.3,
            joint_names: ("left_wheel_joint".into(), "right_wheel_joint".into()),
            scan_every: 5,
            range_sigma: 0.01,
            fov: 2.0 * PI,
            range_max: 2.5,
            compass_every: 2,
            compass_sigma: 1f64.to_radians(),
            ground_truth: true,
            tf_static: true,
            mount: P2 {
                x: 0.2,
                y: 0.0,
                theta: 0.0,
            },
            filler_bytes: 0,
            seed: 7,
        }
    }
}

/// One message of a bag.
#[derive(Debug, Clone)]
pub struct Item {
    /// Log time (ns).
    pub t_ns: u64,
    /// Topic.
    pub topic: String,
    /// The message.
    pub msg: AnyMessage,
}

/// One piece of the drive: forward speed (m/s) and turn rate (rad/s) held for `secs`.
#[derive(Debug, Clone, Copy)]
struct Leg {
    v: f64,
    w: f64,
    secs: f64,
}

/// The drive: `loops` times around (0,0) → (3,0) → (3,1.2) → (0,1.2) → (0,0), turning
/// 90° left on the spot at each corner.
fn legs(loops: usize) -> Vec<Leg> {
    let turn = Leg {
        v: 0.0,
        w: 0.5,
        secs: FRAC_PI_2 / 0.5,
    };
    let long = Leg {
        v: 0.3,
        w: 0.0,
        secs: 10.0,
    };
    let short = Leg {
        v: 0.3,
        w: 0.0,
        secs: 4.0,
    };
    (0..loops)
        .flat_map(|_| [long, turn, short, turn, long, turn, short, turn])
        .collect()
}

/// The true state at `t` seconds: pose and the true wheel angles (left, right).
fn truth_at(legs: &[Leg], t: f64) -> (P2, f64, f64) {
    let mut pose = P2 {
        x: 0.0,
        y: 0.0,
        theta: 0.0,
    };
    let (mut pl, mut pr) = (0.0, 0.0);
    let mut start = 0.0;
    for leg in legs {
        let tau = (t - start).clamp(0.0, leg.secs);
        // Exact arc for constant (v, w).
        let th = pose.theta;
        if leg.w == 0.0 {
            pose.x += leg.v * tau * th.cos();
            pose.y += leg.v * tau * th.sin();
        } else {
            let th1 = th + leg.w * tau;
            pose.x += leg.v / leg.w * (th1.sin() - th.sin());
            pose.y -= leg.v / leg.w * (th1.cos() - th.cos());
            pose.theta = th1;
        }
        pl += (leg.v - leg.w * TRACK / 2.0) / WHEEL_RADIUS * tau;
        pr += (leg.v + leg.w * TRACK / 2.0) / WHEEL_RADIUS * tau;
        start += leg.secs;
        if t <= start {
            break;
        }
    }
    (pose, pl, pr)
}

/// Total drive time (s).
fn duration(legs: &[Leg]) -> f64 {
    legs.iter().map(|l| l.secs).sum()
}

/// The four walls as segments.
pub fn walls() -> [([f64; 2], [f64; 2]); 4] {
    [
        ([ROOM_X0, ROOM_Y0], [ROOM_X1, ROOM_Y0]),
        ([ROOM_X1, ROOM_Y0], [ROOM_X1, ROOM_Y1]),
        ([ROOM_X1, ROOM_Y1], [ROOM_X0, ROOM_Y1]),
        ([ROOM_X0, ROOM_Y1], [ROOM_X0, ROOM_Y0]),
    ]
}

/// Distance along the ray from `(ox, oy)` in direction `a` to the nearest wall.
fn ray_cast(ox: f64, oy: f64, a: f64) -> f64 {
    let (dx, dy) = (a.cos(), a.sin());
    let mut best = f64::INFINITY;
    for (p, q) in walls() {
        let (ex, ey) = (q[0] - p[0], q[1] - p[1]);
        let den = dx * ey - dy * ex;
        if den.abs() < 1e-12 {
            continue;
        }
        let (wx, wy) = (p[0] - ox, p[1] - oy);
        let t = (wx * ey - wy * ex) / den;
        let u = (wx * dy - wy * dx) / den;
        if t > 0.0 && (-1e-9..=1.0 + 1e-9).contains(&u) {
            best = best.min(t);
        }
    }
    best
}

/// A `nav_msgs/Odometry` at `t_ns` with pose `p` in frame `odom`.
pub fn odometry(t_ns: u64, p: &P2) -> Odometry {
    build::odometry(t_ns, &ekf_core::Pose2::new(p.x, p.y, p.theta), "odom")
}

/// A joint state with the given names, positions and velocities.
pub fn joint_state(t_ns: u64, names: (&str, &str), pos: [f64; 2], vel: [f64; 2]) -> JointState {
    JointState {
        header: header(t_ns, ""),
        name: vec![names.0.into(), names.1.into()],
        position: pos.to_vec(),
        velocity: vel.to_vec(),
        effort: Vec::new(),
    }
}

/// A compass reading with heading `yaw` and variance `var`.
pub fn imu(t_ns: u64, yaw: f64, var: f64) -> Imu {
    let mut msg = Imu {
        header: header(t_ns, "compass"),
        orientation: Quaternion::from_yaw(yaw),
        ..Imu::default()
    };
    msg.orientation_covariance[8] = var;
    msg.angular_velocity_covariance[0] = -1.0;
    msg.linear_acceleration_covariance[0] = -1.0;
    msg
}

/// Stamp of motion period `k`: 100 ms apart plus a sub-microsecond jitter, so every
/// stamp has its own nanoseconds.
pub fn motion_stamp(k: usize) -> u64 {
    T0_NS + k as u64 * DT_NS + (k as u64 * 37) % 1000
}

/// Stamp of the scan taken at motion period `k`: 500 ns after the motion stamp, so it has
/// its own TUM row while the robot has not moved measurably (the scans are ray-cast from
/// the pose at the motion stamp; the replay brings the state to the scan's stamp at the
/// last motion rate, which over 500 ns is negligible).
pub fn scan_stamp(k: usize) -> u64 {
    motion_stamp(k) + 500
}

/// Stamp of the compass reading at motion period `k`: 1 µs after the motion stamp, after
/// the scan, so the map built from the first scan is not rotated by the first reading's
/// noise.
pub fn compass_stamp(k: usize) -> u64 {
    motion_stamp(k) + 1_000
}

/// The messages of `s`, in log-time order (ties in the order written).
pub fn build(s: &Scenario) -> Vec<Item> {
    let legs = legs(s.loops);
    let total = duration(&legs);
    let mut steps = (total / (DT_NS as f64 * 1e-9)).floor() as usize;
    if let Some(m) = s.max_steps {
        steps = steps.min(m);
    }
    let rel = |t_ns: u64| (t_ns - T0_NS) as f64 * 1e-9;
    let mut rng = Rng::new(s.seed);
    let mut items = Vec::new();
    let push = |items: &mut Vec<Item>, t_ns: u64, topic: &str, msg: AnyMessage| {
        items.push(Item {
            t_ns,
            topic: topic.into(),
            msg,
        })
    };
    if s.tf_static {
        let tf = TransformStamped {
            header: header(T0_NS, "base_link"),
            child_frame_id: "laser".into(),
            transform: Transform {
                translation: Vector3 {
                    x: s.mount.x,
                    y: s.mount.y,
                    z: 0.3,
                },
                rotation: Quaternion::from_yaw(s.mount.theta),
            },
        };
        push(
            &mut items,
            T0_NS,
            "/tf_static",
            AnyMessage::TFMessage(TFMessage {
                transforms: vec![tf],
            }),
        );
    }
    let (sl, sr) = s.wheel_scale;
    let mut previous: Option<(u64, f64, f64)> = None;
    // Recorded wheel angles: scaled true increments plus noise.
    let (mut ml, mut mr) = (0.0, 0.0);
    let mut last_true = (0.0, 0.0);
    let mut odom = P2 {
        x: 0.0,
        y: 0.0,
        theta: 0.0,
    };
    for k in 0..=steps {
        let t = motion_stamp(k);
        let (truth, pl, pr) = truth_at(&legs, rel(t));
        let dt = DT_NS as f64 * 1e-9;
        if k > 0 {
            ml += (pl - last_true.0) * sl + rng.gauss(s.wheel_noise) * dt;
            mr += (pr - last_true.1) * sr + rng.gauss(s.wheel_noise) * dt;
        }
        last_true = (pl, pr);
        match s.motion {
            MotionTopic::Joints => {
                let vel = match previous {
                    Some((t0, l0, r0)) => {
                        let dt = (t - t0) as f64 * 1e-9;
                        [(ml - l0) / dt, (mr - r0) / dt]
                    }
                    None => [0.0, 0.0],
                };
                let names = (s.joint_names.0.as_str(), s.joint_names.1.as_str());
                push(
                    &mut items,
                    t,
                    "/joint_states",
                    AnyMessage::JointState(joint_state(t, names, [ml, mr], vel)),
                );
            }
            MotionTopic::Odom => {
                if let Some((_, l0, r0)) = previous {
                    let (dl, dr) = ((ml - l0) * WHEEL_RADIUS, (mr - r0) * WHEEL_RADIUS);
                    let (ds, dth) = ((dl + dr) / 2.0, (dr - dl) / TRACK);
                    let mid = odom.theta + dth / 2.0;
                    odom.x += ds * mid.cos();
                    odom.y += ds * mid.sin();
                    odom.theta += dth;
                }
                push(
                    &mut items,
                    t,
                    "/odom",
                    AnyMessage::Odometry(odometry(t, &odom)),
                );
            }
            MotionTopic::None => {}
        }
        previous = Some((t, ml, mr));
        if s.ground_truth {
            push(
                &mut items,
                t,
                "/ground_truth",
                AnyMessage::Odometry(odometry(t, &truth)),
            );
        }
        if s.compass_every > 0 && k % s.compass_every == 0 {
            let tc = compass_stamp(k);
            let (tp, _, _) = truth_at(&legs, rel(tc));
            let yaw = tp.theta + rng.gauss(s.compass_sigma);
            let var = s.compass_sigma * s.compass_sigma;
            push(
                &mut items,
                tc,
                "/compass",
                AnyMessage::Imu(imu(tc, yaw, var)),
            );
        }
        if s.scan_every > 0 && k % s.scan_every == 0 {
            let ts = scan_stamp(k);
            let (tp, _, _) = truth_at(&legs, rel(ts));
            push(
                &mut items,
                ts,
                "/scan",
                AnyMessage::LaserScan(scan(
                    ts,
                    &tp.compose(&s.mount),
                    s.fov,
                    s.range_max,
                    s.range_sigma,
                    &mut rng,
                )),
            );
            if s.ground_truth {
                push(
                    &mut items,
                    ts,
                    "/ground_truth",
                    AnyMessage::Odometry(odometry(ts, &tp)),
                );
            }
        }
        if s.filler_bytes > 0 && k % 10 == 0 {
            let tf = t + 70_000_000;
            // Random ranges: incompressible, so the bag spans several chunks.
            let ranges = (0..s.filler_bytes / 4)
                .map(|_| (rng.next_u64() % 10_000) as f32 * 1e-3)
                .collect();
            push(
                &mut items,
                tf,
                FILLER_TOPIC,
                AnyMessage::LaserScan(LaserScan {
                    header: header(tf, "lidar3d"),
                    angle_increment: 1e-4,
                    range_max: 10.0,
                    ranges,
                    ..LaserScan::default()
                }),
            );
        }
    }
    items.sort_by_key(|i| i.t_ns);
    items
}

/// A scan from the laser at `laser` (world frame): `BEAMS` beams evenly over `fov`.
pub fn scan(
    t_ns: u64,
    laser: &P2,
    fov: f64,
    range_max: f64,
    sigma: f64,
    rng: &mut Rng,
) -> LaserScan {
    let angle_min = (-fov / 2.0) as f32;
    let inc = (fov / (BEAMS - 1) as f64) as f32;
    let ranges = (0..BEAMS)
        .map(|i| {
            let a = f64::from(angle_min) + i as f64 * f64::from(inc);
            let r = ray_cast(laser.x, laser.y, laser.theta + a);
            let noisy = r + rng.gauss(sigma);
            if noisy > range_max {
                f32::INFINITY
            } else {
                noisy as f32
            }
        })
        .collect();
    LaserScan {
        header: header(t_ns, "laser"),
        angle_min,
        angle_max: angle_min + inc * (BEAMS - 1) as f32,
        angle_increment: inc,
        time_increment: 0.0,
        scan_time: 0.5,
        range_min: 0.05,
        range_max: range_max as f32,
        ranges,
        intensities: Vec::new(),
    }
}

/// Writes `items` to `path` in order.
pub fn write_bag(path: &Path, items: &[Item]) {
    let mut w = BagWriter::create(path).expect("create bag");
    for i in items {
        w.write_any(&i.topic, i.t_ns, &i.msg)
            .expect("write message");
    }
    w.finish().expect("finish bag");
}

/// Builds and writes the scenario to `dir/name`; returns the path and the items.
pub fn write_scenario(dir: &Path, name: &str, s: &Scenario) -> (PathBuf, Vec<Item>) {
    let items = build(s);
    let path = dir.join(name);
    write_bag(&path, &items);
    (path, items)
}

/// Runs the real `ekf` binary.
pub fn ekf(args: &[&str]) -> Output {
    ekf_bin::ekf().args(args).output().expect("run ekf")
}

/// stdout and stderr as text.
pub fn texts(out: &Output) -> (String, String) {
    (
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Runs `ekf replay LOG --json ARGS...`, expects success and returns the summary.
pub fn replay_json(log: &Path, args: &[&str]) -> serde_json::Value {
    let log = log.to_str().expect("utf-8 path");
    let mut all = vec!["replay", log, "--json"];
    all.extend_from_slice(args);
    let out = ekf(&all);
    let (stdout, stderr) = texts(&out);
    assert!(
        out.status.success(),
        "ekf {all:?} failed ({:?}): {stderr}",
        out.status
    );
    serde_json::from_str(&stdout).unwrap_or_else(|e| panic!("summary is not JSON ({e}): {stdout}"))
}

/// Parses a TUM file written by `ekf`: `(stamp text, [x y z qx qy qz qw])` per row.
pub fn read_tum_rows(path: &Path) -> Vec<(String, [f64; 7])> {
    let text = std::fs::read_to_string(path)
        .unwrap_or_else(|e| panic!("{}: cannot read TUM file: {e}", path.display()));
    text.lines()
        .filter(|l| !l.trim().is_empty() && !l.starts_with('#'))
        .map(|l| {
            let f: Vec<&str> = l.split_whitespace().collect();
            assert_eq!(f.len(), 8, "TUM row {l:?}");
            let mut v = [0.0; 7];
            for (i, x) in f[1..].iter().enumerate() {
                v[i] = x.parse().unwrap_or_else(|e| panic!("TUM field {x:?}: {e}"));
            }
            (f[0].to_string(), v)
        })
        .collect()
}

/// A nanosecond stamp as TUM text (decimal seconds, 9 digits).
pub fn stamp_text(t_ns: u64) -> String {
    format!("{}.{:09}", t_ns / 1_000_000_000, t_ns % 1_000_000_000)
}

/// Messages per topic of a bag, by reading every message (fails on damage).
pub fn count_messages(path: &Path) -> BTreeMap<String, u64> {
    let bag = BagReader::open(path)
        .unwrap_or_else(|e| panic!("{}: output bag does not open: {e}", path.display()));
    let mut counts = BTreeMap::new();
    for m in bag.messages().expect("message stream") {
        let m = m.unwrap_or_else(|e| panic!("output bag is damaged: {e}"));
        *counts.entry(m.topic().to_owned()).or_insert(0) += 1;
    }
    counts
}
