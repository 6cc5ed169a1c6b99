//! The real MRPT export (`shared/data/2006-01ENE-21-SENA_Telecom_Faculty_one_loop_only
//! .carmenlike.txt`): counts, time span, scan shape and laser mount.

mod import_common;

use ekf_cli::import::{open_log, read_mrpt, ImportRecord};
use import_common::{assert_pose, shared_data};

const FILE: &str = "2006-01ENE-21-SENA_Telecom_Faculty_one_loop_only.carmenlike.txt";

#[test]
fn malaga_loop_counts_span_and_scans() {
    let reader = open_log(&shared_data(FILE)).unwrap();
    let mut records = read_mrpt(reader);
    let all = records.by_ref().collect::<Result<Vec<_>, _>>().unwrap();
    let stats = records.stats();
    assert_eq!(
        (stats.scans, stats.odometry, stats.references),
        (225, 224, 0)
    );
    assert_eq!((stats.comment_lines, stats.unknown_lines), (0, 0));
    assert_eq!(stats.backwards_time, 0);
    assert_eq!(stats.t_min_ns, Some(1_137_834_225_713_386_000));
    assert_eq!(stats.t_max_ns, Some(1_137_834_284_788_331_000));
    // 59.07 s from the first to the last record (the data README rounds to 58.8 s).
    assert_eq!(stats.span_ns(), 59_074_945_000);

    // π as the export writes it, rounded to 6 decimals.
    let aperture: f64 = "3.141593".parse().unwrap();
    let mut invalid = 0usize;
    for record in &all {
        if let ImportRecord::Scan(scan) = record {
            assert_eq!(scan.ranges.len(), 361);
            assert_pose(&scan.mount, (0.78, 0.0, 0.0), 0.0);
            assert_eq!(scan.range_max, 80.0);
            assert!((scan.angle_min + aperture / 2.0).abs() < 1e-12);
            assert!((scan.angle_increment - 0.5f64.to_radians()).abs() < 1e-8);
            invalid += scan
                .ranges
                .iter()
                .filter(|&&r| f64::from(r) >= scan.range_max)
                .count();
        }
    }
    assert!(invalid > 0, "invalid beams are kept at max_range");
    let ImportRecord::Odometry(last) = all[all.len() - 2] else {
        panic!("odometry expected")
    };
    assert_pose(&last.pose, (-4.8024, -21.1637, -1.86234), 0.0);
}
