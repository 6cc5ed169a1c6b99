//! Golden tests: small hand-written CARMEN and MRPT excerpts → the exact records.

mod import_common;

use ekf_cli::import::{
    read_carmen, read_mrpt, CarmenFlavour, CarmenOptions, ImportRecord, ImportStats, RangeMax,
    RangeMaxSource, RepairCount, Scan, SyntheticCompass, TimeRepairs,
};
use import_common::{assert_pose, kind};
use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};

const CARMEN: &str = include_str!("fixtures/carmen_corrected.log");
const MRPT: &str = include_str!("fixtures/mrpt_excerpt.txt");
const TOL: f64 = 1e-12;

fn carmen(options: CarmenOptions) -> (Vec<ImportRecord>, ImportStats) {
    let mut reader = read_carmen(CARMEN.as_bytes(), options);
    let records = reader.by_ref().collect::<Result<Vec<_>, _>>().unwrap();
    (records, reader.stats().clone())
}

fn odom(r: &ImportRecord, t_ns: u64, pose: (f64, f64, f64)) {
    let ImportRecord::Odometry(o) = r else {
        panic!("expected odometry, got {r:?}")
    };
    assert_eq!(o.t_ns, t_ns);
    assert_pose(&o.pose, pose, TOL);
}

fn reference(r: &ImportRecord, t_ns: u64, pose: (f64, f64, f64)) {
    let ImportRecord::Reference(o) = r else {
        panic!("expected reference, got {r:?}")
    };
    assert_eq!(o.t_ns, t_ns);
    assert_pose(&o.pose, pose, TOL);
}

fn scan(r: &ImportRecord) -> &Scan {
    let ImportRecord::Scan(s) = r else {
        panic!("expected scan, got {r:?}")
    };
    s
}

#[test]
fn corrected_carmen_rechains_odometry_and_yields_references() {
    let (r, stats) = carmen(CarmenOptions::default());
    let kinds: Vec<_> = r.iter().map(kind).collect();
    assert_eq!(
        kinds,
        ["odom", "odom", "scan", "ref", "odom", "scan", "ref", "odom", "odom"]
    );

    odom(&r[0], 1_000_000_000, (0.0, 0.0, 0.0));
    odom(&r[1], 2_000_000_000, (1.0, 0.0, 0.0));
    assert_eq!(
        scan(&r[2]),
        &Scan {
            t_ns: 2_000_000_000,
            angle_min: -FRAC_PI_2,
            angle_increment: FRAC_PI_4,
            range_min: 0.0,
            range_max: 4.0, // from PARAM robot_front_laser_max
            ranges: vec![1.0, 2.5, 4.0, 0.75],
            mount: ekf_core::Pose2::new(0.0, 0.0, 0.0),
        }
    );
    reference(&r[3], 2_000_000_000, (1.2, 0.3, 0.1));
    // 1 m straight ahead of the reset, chained onto the raw pose (1, 0, 0).
    odom(&r[4], 3_500_000_000, (2.0, 0.0, 0.0));
    assert_eq!(scan(&r[5]).ranges, [0.5, 0.6, 0.7, 0.8]);
    reference(&r[6], 3_500_000_000, (2.3, 0.5, 0.2));
    // Turn in place by 0.3 rad, then 0.5 m ahead.
    odom(&r[7], 4_250_000_000, (2.0, 0.0, 0.3));
    odom(
        &r[8],
        5_125_000_000,
        (2.0 + 0.5 * 0.3f64.cos(), 0.5 * 0.3f64.sin(), 0.3),
    );

    assert_eq!(
        stats,
        ImportStats {
            odometry: 5,
            scans: 2,
            references: 2,
            compass: 0,
            odometry_resets: 2,
            t_min_ns: Some(1_000_000_000),
            t_max_ns: Some(5_125_000_000),
            backwards_time: 0,
            time_repairs: TimeRepairs::default(),
            duplicates: RepairCount::default(),
            invalid_ranges: RepairCount::default(),
            laser_range_max: Some(RangeMax {
                value: 4.0,
                source: RangeMaxSource::Param,
            }),
            comment_lines: 1,
            param_lines: 1,
            neff_lines: 2,
            unknown_lines: 0,
        }
    );
    assert_eq!(stats.span_ns(), 4_125_000_000);
}

#[test]
fn forced_corrected_flavour_gives_the_same_records() {
    let options = CarmenOptions {
        flavour: CarmenFlavour::Corrected,
        ..CarmenOptions::default()
    };
    assert_eq!(carmen(options), carmen(CarmenOptions::default()));
}

#[test]
fn plain_flavour_keeps_odom_poses_as_written() {
    let options = CarmenOptions {
        flavour: CarmenFlavour::Plain,
        ..CarmenOptions::default()
    };
    let (r, stats) = carmen(options);
    let kinds: Vec<_> = r.iter().map(kind).collect();
    assert_eq!(
        kinds,
        ["odom", "odom", "scan", "odom", "odom", "scan", "odom", "odom", "odom"]
    );
    // The reset's timestamp 0, repaired halfway between its neighbours' (2 s and 3.5 s).
    odom(&r[3], 2_750_000_000, (1.2, 0.3, 0.1));
    odom(
        &r[4],
        3_500_000_000,
        (2.195004165278026, 0.39983341664682814, 0.1),
    );
    odom(
        &r[8],
        5_125_000_000,
        (2.738791280945186, 0.7397127693021015, 0.5),
    );
    assert_eq!(stats.references, 0);
    assert_eq!(stats.odometry_resets, 0);
    assert_eq!(stats.backwards_time, 0);
    assert_eq!(
        stats.time_repairs.zero.first_lines,
        [6, 10],
        "the two reset records have timestamp 0"
    );
}

#[test]
fn synthetic_compass_follows_each_reference() {
    let compass = SyntheticCompass {
        sigma_deg: 2.0,
        seed: 42,
    };
    let options = CarmenOptions {
        synthetic_compass: Some(compass),
        ..CarmenOptions::default()
    };
    let (r, stats) = carmen(options);
    let kinds: Vec<_> = r.iter().map(kind).collect();
    assert_eq!(
        kinds,
        [
            "odom", "odom", "scan", "ref", "compass", "odom", "scan", "ref", "compass", "odom",
            "odom"
        ]
    );
    assert_eq!(stats.compass, 2);
    for (i, truth) in [(4, 0.1), (8, 0.2)] {
        let ImportRecord::Compass(c) = &r[i] else {
            panic!()
        };
        assert!(c.synthetic);
        assert_eq!(c.t_ns, r[i - 1].t_ns());
        assert!((c.heading - truth).abs() < 5.0 * 2f64.to_radians(), "{c:?}");
        assert_ne!(c.heading, truth);
        assert!((c.variance - 2f64.to_radians().powi(2)).abs() < 1e-15);
    }
    assert_eq!(carmen(options).0, r, "same seed, same headings");
    let other = CarmenOptions {
        synthetic_compass: Some(SyntheticCompass {
            seed: 43,
            ..compass
        }),
        ..options
    };
    assert_ne!(carmen(other).0, r, "another seed, other headings");
}

#[test]
fn robotlaser1_gives_the_mount_from_laser_and_robot_poses() {
    // Robot at (1, 2) facing +y; laser 0.5 m ahead of it, so at (1, 2.5) in the world.
    let line = "ROBOTLASER1 0 -1.5 3.0 0.75 30.0 0.01 0 5 1 2 3 4 30 2 0.5 0.6 \
                1 2.5 1.5707963267948966 1 2 1.5707963267948966 0 0 0.5 0.3 0 12.5 host 12.6\n";
    let records: Vec<_> = read_carmen(line.as_bytes(), CarmenOptions::default())
        .collect::<Result<_, _>>()
        .unwrap();
    assert_eq!(records.len(), 1);
    let s = scan(&records[0]);
    assert_eq!(s.t_ns, 12_500_000_000);
    assert_eq!(
        (s.angle_min, s.angle_increment, s.range_max),
        (-1.5, 0.75, 30.0)
    );
    assert_eq!(s.ranges, [1.0, 2.0, 3.0, 4.0, 30.0]);
    assert_pose(&s.mount, (0.5, 0.0, 0.0), TOL);
}

#[test]
fn mrpt_excerpt_gives_exact_records() {
    let mut reader = read_mrpt(MRPT.as_bytes());
    let r = reader.by_ref().collect::<Result<Vec<_>, _>>().unwrap();
    let kinds: Vec<_> = r.iter().map(kind).collect();
    assert_eq!(kinds, ["scan", "odom", "scan", "odom"]);
    // π as the export writes it, rounded to 6 decimals.
    let aperture: f64 = "3.141593".parse().unwrap();
    assert_eq!(
        scan(&r[0]),
        &Scan {
            t_ns: 1_137_834_225_713_386_000,
            angle_min: -aperture / 2.0,
            angle_increment: aperture / 4.0,
            range_min: 0.0,
            range_max: 80.0,
            ranges: vec![1.69, 80.0, 2.5, 3.25, 1.0],
            mount: ekf_core::Pose2::new(0.78, 0.0, 0.0),
        }
    );
    odom(&r[1], 1_137_834_225_843_573_000, (0.0, 0.0, 0.0));
    let clockwise = scan(&r[2]);
    assert_eq!(clockwise.t_ns, 1_137_834_225_973_760_000);
    assert_eq!(
        (clockwise.angle_min, clockwise.angle_increment),
        (aperture / 2.0, -aperture / 2.0)
    );
    odom(
        &r[3],
        1_137_834_226_083_918_000,
        (0.1, -0.05, 3.2 - 2.0 * PI),
    );
    let stats = reader.stats();
    assert_eq!(
        (stats.scans, stats.odometry, stats.comment_lines),
        (2, 2, 1)
    );
    assert_eq!(stats.span_ns(), 370_532_000);
}
