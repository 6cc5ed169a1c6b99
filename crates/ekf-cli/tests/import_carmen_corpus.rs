//! Every shared CARMEN log (`shared/data/aces-corrected.log.gz` and `shared/data/carmen/`)
//! imports as it is, with the defaults: one reference per scan, times in file order that
//! never go back, each kind of timestamp repair counted, and the laser's no-return value
//! taken from the readings.

mod import_common;

use ekf_cli::import::{open_log, read_carmen, CarmenOptions, ImportRecord, RangeMaxSource};
use import_common::shared_data;

struct Expected {
    file: &'static str,
    scans: u64,
    clock_broken: bool,
    /// The no-return value the readings saturate at (m), if they do within the first
    /// records.
    saturation: Option<f64>,
}

const LOGS: [Expected; 9] = [
    Expected {
        file: "aces-corrected.log.gz",
        scans: 440,
        clock_broken: false,
        saturation: Some(50.0),
    },
    Expected {
        file: "carmen/csail-corrected.log.gz",
        scans: 406,
        clock_broken: true,
        saturation: Some(81.91),
    },
    Expected {
        file: "carmen/edmonton-corrected.log.gz",
        scans: 340,
        clock_broken: false,
        saturation: Some(51.16),
    },
    Expected {
        file: "carmen/fhw-corrected.log.gz",
        scans: 488,
        clock_broken: false,
        saturation: None,
    },
    Expected {
        file: "carmen/freiburg-101-corrected.log.gz",
        scans: 292,
        clock_broken: false,
        saturation: Some(81.91),
    },
    Expected {
        file: "carmen/freiburg-campus-corrected.log.gz",
        scans: 2008,
        clock_broken: true,
        saturation: Some(81.91),
    },
    Expected {
        file: "carmen/infinite-corridor-corrected.log.gz",
        scans: 1941,
        clock_broken: true,
        saturation: Some(51.11),
    },
    Expected {
        file: "carmen/orebro-corrected.log.gz",
        scans: 237,
        clock_broken: true,
        saturation: Some(32.767),
    },
    Expected {
        file: "carmen/seattle-corrected.log.gz",
        scans: 241,
        clock_broken: false,
        saturation: Some(81.91),
    },
];

#[test]
fn every_shared_log_imports_with_the_defaults() {
    for expected in &LOGS {
        let reader = open_log(&shared_data(expected.file)).unwrap();
        let mut records = read_carmen(reader, CarmenOptions::default());
        let all: Vec<ImportRecord> = records
            .by_ref()
            .collect::<Result<_, _>>()
            .unwrap_or_else(|e| panic!("{}: {e}", expected.file));
        let stats = records.stats();
        let name = expected.file;
        assert_eq!(stats.scans, expected.scans, "{name}");
        assert_eq!(
            stats.references, expected.scans,
            "{name}: a reference per scan"
        );
        assert_eq!(
            stats.odometry_resets, expected.scans,
            "{name}: a reset per scan"
        );
        assert_eq!(stats.backwards_time, 0, "{name}");
        assert!(
            all.windows(2).all(|w| w[0].t_ns() <= w[1].t_ns()),
            "{name}: times never go back"
        );
        assert!(all.iter().all(|r| r.t_ns() > 0), "{name}: no zero time");
        assert_eq!(
            stats.time_repairs.clock_broken, expected.clock_broken,
            "{name}"
        );
        let limit = stats.laser_range_max.expect("scans have a range limit");
        match expected.saturation {
            Some(s) => {
                assert_eq!(limit.source, RangeMaxSource::Saturation, "{name}");
                assert!((limit.value - 0.99 * s).abs() < 1e-4, "{name}: {limit:?}");
            }
            None => assert_ne!(limit.source, RangeMaxSource::Saturation, "{name}"),
        }
        // Each reference shares its scan's time.
        for w in all.windows(2) {
            if let [ImportRecord::Scan(s), ImportRecord::Reference(r)] = w {
                assert_eq!(s.t_ns, r.t_ns, "{name}");
            }
        }
    }
}

#[test]
fn the_reset_records_of_seattle_are_recognised_whatever_their_stamp() {
    // Seattle's reset records carry stamps like -1.63023 (line 19765) as well as 0; the
    // rest of its clock is good, so nothing else needs repair.
    let reader = open_log(&shared_data("carmen/seattle-corrected.log.gz")).unwrap();
    let mut records = read_carmen(reader, CarmenOptions::default());
    for r in records.by_ref() {
        r.unwrap();
    }
    let stats = records.stats();
    assert_eq!(stats.odometry_resets, 241);
    assert_eq!(stats.time_repairs.repaired(), 0);
    assert!(!stats.time_repairs.clock_broken);
}
