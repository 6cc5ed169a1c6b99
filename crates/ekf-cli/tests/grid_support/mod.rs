//! A test fixture generator: an occupancy grid of a log made as a SLAM package's mapper
//! makes one (GMapping's `map_saver` output), independently of `ekf map export-grid` —
//! every beam of every scan, placed at the log's reference pose, traced through a count
//! grid: the cells it crosses are misses, the cell it ends in a hit; a cell is occupied
//! when more than 25 % of its visits were hits (GMapping's `occ_thresh`), free when
//! visited otherwise, unknown when never visited. Written as `map_saver` writes it: a
//! binary PGM (0 occupied, 254 free, 205 unknown) and a YAML beside it.

use ekf_cli::mcap_io::BagReader;
use ekf_cli::ros2::AnyMessage;
use ekf_core::Pose2;
use std::path::Path;

/// GMapping's default `occ_thresh`.
const OCC_THRESH: f64 = 0.25;

/// Writes `<stem>.pgm` and `<stem>.yaml` into `dir` for the scans of `log` at its
/// `/ground_truth` poses (laser at the robot origin, as in the bundled logs), cells of
/// `resolution`; returns the YAML's path.
pub fn gmapping_style_grid(
    log: &Path,
    resolution: f64,
    dir: &Path,
    stem: &str,
) -> std::path::PathBuf {
    let bag = BagReader::open(log).unwrap();
    let mut reference: Vec<(u64, Pose2<f64>)> = Vec::new();
    let mut scans = Vec::new();
    for m in bag.messages().unwrap() {
        let m = m.unwrap();
        match m.topic() {
            "/ground_truth" => {
                if let Some(p) = ekf_cli::replay::reference_pose(&m.decode().unwrap()) {
                    reference.push((m.log_time, p));
                }
            }
            "/scan" => {
                if let AnyMessage::LaserScan(s) = m.decode().unwrap() {
                    scans.push((m.log_time, s));
                }
            }
            _ => {}
        }
    }
    // Beam end points in the world, with the sensor position they were seen from.
    let mut beams: Vec<([f64; 2], [f64; 2])> = Vec::new();
    for (t, scan) in &scans {
        let Some(&(_, pose)) = reference
            .iter()
            .min_by_key(|(rt, _)| rt.abs_diff(*t))
            .filter(|(rt, _)| rt.abs_diff(*t) <= 50_000_000)
        else {
            continue;
        };
        for (i, &r) in scan.ranges.iter().enumerate() {
            if !(r.is_finite() && r > scan.range_min && r < scan.range_max) {
                continue;
            }
            let a =
                pose.theta + f64::from(scan.angle_min) + i as f64 * f64::from(scan.angle_increment);
            let r = f64::from(r);
            beams.push((
                [pose.x, pose.y],
                [pose.x + r * a.cos(), pose.y + r * a.sin()],
            ));
        }
    }
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for (s, e) in &beams {
        for p in [s, e] {
            for k in 0..2 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
    }
    let origin = [lo[0] - 1.0, lo[1] - 1.0];
    let w = ((hi[0] - origin[0] + 1.0) / resolution).ceil() as usize;
    let h = ((hi[1] - origin[1] + 1.0) / resolution).ceil() as usize;
    let (mut hits, mut visits) = (vec![0u32; w * h], vec![0u32; w * h]);
    let cell = |p: [f64; 2]| {
        let ix = ((p[0] - origin[0]) / resolution).floor() as usize;
        let iy = ((p[1] - origin[1]) / resolution).floor() as usize;
        iy * w + ix
    };
    for (s, e) in &beams {
        let end = cell(*e);
        let len = ((e[0] - s[0]).hypot(e[1] - s[1]) / (0.5 * resolution)).ceil() as usize;
        let mut last = usize::MAX;
        for k in 0..len {
            let f = k as f64 / len as f64;
            let c = cell([s[0] + (e[0] - s[0]) * f, s[1] + (e[1] - s[1]) * f]);
            if c != end && c != last {
                visits[c] += 1;
                last = c;
            }
        }
        visits[end] += 1;
        hits[end] += 1;
    }
    // map_saver's image: top row first.
    let mut pgm =
        format!("P5\n# CREATOR: test fixture {resolution:.3} m/pix\n{w} {h}\n255\n").into_bytes();
    for iy in (0..h).rev() {
        for ix in 0..w {
            let (n, v) = (hits[iy * w + ix], visits[iy * w + ix]);
            pgm.push(if v == 0 {
                205
            } else if f64::from(n) / f64::from(v) > OCC_THRESH {
                0
            } else {
                254
            });
        }
    }
    std::fs::write(dir.join(format!("{stem}.pgm")), pgm).unwrap();
    let yaml = dir.join(format!("{stem}.yaml"));
    std::fs::write(
        &yaml,
        format!(
            "image: {stem}.pgm\nresolution: {resolution:.6}\norigin: [{:.6}, {:.6}, 0.000000]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n\n",
            origin[0], origin[1]
        ),
    )
    .unwrap();
    yaml
}
