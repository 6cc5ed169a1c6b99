//! Bad input: every error names the line and the field, ends the iteration after the
//! good records before it, and no input (random bytes, mutated lines) makes a panic.

mod import_common;

use ekf_cli::import::{read_carmen, read_mrpt, CarmenOptions, ImportError, ImportRecord};
use proptest::prelude::*;

/// All records before the first error and the error's message; asserts that the
/// iteration ends right after the error.
fn carmen_until_error(text: &[u8]) -> (Vec<ImportRecord>, String) {
    let mut reader = read_carmen(text, CarmenOptions::default());
    let mut ok = Vec::new();
    for item in reader.by_ref() {
        match item {
            Ok(r) => ok.push(r),
            Err(e) => {
                assert!(reader.next().is_none(), "iteration goes on after an error");
                return (ok, e.to_string());
            }
        }
    }
    panic!("no error for {:?}", String::from_utf8_lossy(text));
}

fn mrpt_error(text: &str) -> String {
    read_mrpt(text.as_bytes())
        .find_map(Result::err)
        .map(|e| e.to_string())
        .expect("an error")
}

const GOOD_ODOM: &str = "ODOM 1 2 0.5 0 0 0 7.25 host 7.25\n";

#[test]
fn truncated_line_names_the_record_and_field_count() {
    let text = format!("{GOOD_ODOM}# comment\nODOM 1 2\n");
    let (ok, e) = carmen_until_error(text.as_bytes());
    assert_eq!(ok.len(), 1, "the good record before the error is yielded");
    assert_eq!(e, "line 3: ODOM: expected 10 fields, the line has 3");
}

#[test]
fn non_numeric_field_is_named() {
    let text = "FLASER 4 1 2 3 4 abc 0 0 0 0 0 5.0 host 5.0\n";
    let (_, e) = carmen_until_error(text.as_bytes());
    assert_eq!(
        e,
        "line 1: FLASER field 7 (x): expected a finite number, found 'abc'"
    );
}

#[test]
fn wrong_reading_count_is_reported() {
    let ranges = vec!["1.0"; 139].join(" ");
    let text = format!("FLASER 180 {ranges} 0 0 0 0 0 0 5.0 host 5.0\n");
    let (_, e) = carmen_until_error(text.as_bytes());
    assert_eq!(
        e,
        "line 1: FLASER declares 180 readings: expected 191 fields, the line has 150"
    );
}

#[test]
fn nan_and_infinity_are_rejected() {
    let (_, e) = carmen_until_error(b"FLASER 2 1.0 NaN 0 0 0 0 0 0 5.0 host 5.0\n");
    assert_eq!(
        e,
        "line 1: FLASER field 4 (range): expected a finite number, found 'NaN'"
    );
    let (_, e) = carmen_until_error(b"ODOM 1 inf 0 0 0 0 1 h 1\n");
    assert_eq!(
        e,
        "line 1: ODOM field 3 (y): expected a finite number, found 'inf'"
    );
}

/// A log appended to itself (`cat log.gz log.gz`: two gzip members) starts over at its
/// first stamp: the first copy is imported, and the error names the line where the
/// second begins; one stray stamp back at the start is only a repaired stamp.
#[test]
fn a_log_that_starts_over_is_imported_up_to_the_restart() {
    let copy: String = (0..30)
        .map(|i| {
            format!(
                "ODOM {i} 0 0 0 0 0 {t} host {t}\n",
                t = 100.0 + 0.1 * f64::from(i)
            )
        })
        .collect();
    let (records, e) = carmen_until_error(format!("{copy}{copy}").as_bytes());
    assert_eq!(records.len(), 30);
    assert_eq!(
        e,
        "line 31: the log starts over: from here the stamps run again from 100.000 s, back \
         at the first record's 100.000 s after 2.9 s of log (a second copy appended, e.g. a \
         second gzip member?); the records before line 31 are imported, the rest is not"
    );
    // A stray stamp back at the start, then the log goes on: repaired, not a restart.
    let later: String = (30..60)
        .map(|i| {
            format!(
                "ODOM {i} 0 0 0 0 0 {t} host {t}\n",
                t = 100.0 + 0.1 * f64::from(i)
            )
        })
        .collect();
    let text = format!("{copy}ODOM 9 0 0 0 0 0 100.0 host 100.0\n{later}");
    let mut reader = read_carmen(text.as_bytes(), CarmenOptions::default());
    assert_eq!(reader.by_ref().map(Result::unwrap).count(), 61);
    assert_eq!(reader.stats().time_repairs.backwards.count, 1);
}

/// A negative reading is no range a scanner measures: read as no return (NaN), the scan
/// kept, and its line counted for the import summary.
#[test]
fn a_negative_range_is_no_return_and_counted_with_its_line() {
    let text = format!("{GOOD_ODOM}FLASER 3 1.0 -2.5 3.0 0 0 0 0 0 0 8.0 host 8.0\n");
    let mut reader = read_carmen(text.as_bytes(), CarmenOptions::default());
    let records: Vec<ImportRecord> = reader.by_ref().map(Result::unwrap).collect();
    let ranges = records
        .iter()
        .find_map(|r| match r {
            ImportRecord::Scan(s) => Some(s.ranges.clone()),
            _ => None,
        })
        .expect("the scan is kept");
    assert_eq!((ranges[0], ranges[2]), (1.0, 3.0));
    assert!(ranges[1].is_nan());
    let counted = &reader.stats().invalid_ranges;
    assert_eq!((counted.count, counted.first_lines.clone()), (1, vec![2]));
}

#[test]
fn bad_timestamp_and_count_are_named() {
    let (_, e) = carmen_until_error(b"ODOM 1 2 3 0 0 0 4s h 1\n");
    assert_eq!(
        e,
        "line 1: ODOM field 8 (timestamp): expected a time in seconds, found '4s'"
    );
    let (_, e) = carmen_until_error(b"FLASER -3 0 0 0\n");
    assert_eq!(
        e,
        "line 1: FLASER field 2 (num_readings): expected a non-negative integer, found '-3'"
    );
}

#[test]
fn a_negative_stamp_is_repaired_or_refused_with_strict() {
    let text = "ODOM 0 0 0 0 0 0 1 h 1\nODOM 1 0 0 0 0 0 -4 h 1\nODOM 2 0 0 0 0 0 3 h 3\n";
    let mut reader = read_carmen(text.as_bytes(), CarmenOptions::default());
    let times: Vec<u64> = reader.by_ref().map(|r| r.unwrap().t_ns()).collect();
    assert_eq!(times, [1_000_000_000, 2_000_000_000, 3_000_000_000]);
    let repairs = &reader.stats().time_repairs;
    assert_eq!(
        (
            repairs.negative.count,
            repairs.negative.first_lines.as_slice()
        ),
        (1, &[2][..])
    );
    let strict = CarmenOptions {
        strict: true,
        ..CarmenOptions::default()
    };
    let e = read_carmen(text.as_bytes(), strict)
        .find_map(Result::err)
        .expect("strict refuses it");
    assert_eq!(
        e.to_string(),
        "line 2: ODOM field 8 (timestamp): the time is negative (--strict refuses repairing it)"
    );
}

#[test]
fn robotlaser1_remission_count_is_checked() {
    let text = "ROBOTLASER1 0 -1.5 3.0 0.75 30.0 0.01 0 2 1 2 5 0.5 0 0 0 0 0 0 0 0 0 0 0 1 h 1\n";
    let (_, e) = carmen_until_error(text.as_bytes());
    assert_eq!(
        e,
        "line 1: ROBOTLASER1 declares 2 readings and 5 remissions: expected 31 fields, the line has 27"
    );
}

#[test]
fn not_text_is_an_error() {
    let (_, e) = carmen_until_error(b"ODOM 1 2 3 0 0 0 1 h 1\n\xff\xfe\n");
    assert_eq!(e, "line 2: not UTF-8 text");
}

#[test]
fn mrpt_errors_name_line_and_field() {
    let ok = "RAWSCAN 1.5 3 3.14 80 0.78 0 0 1 2 3 label= rightToLeft=1\n";
    assert_eq!(
        mrpt_error(&format!("{ok}RAWSCAN 1.5 3 3.14 80 0.78 0 0 1 2\n")),
        "line 2: RAWSCAN declares 3 readings: expected 11 fields, the line has 10"
    );
    assert_eq!(
        mrpt_error("RAWSCAN 1.5 3 3.14 80 0.78 0 0 1 nan 3\n"),
        "line 1: RAWSCAN field 10 (range): expected a finite number, found 'nan'"
    );
    assert_eq!(
        mrpt_error("RAWSCAN 1.5 3 3.14 80 0.78 0 0 1 2 3 4\n"),
        "line 1: RAWSCAN field 12 (trailing): expected key=value after the readings, found '4'"
    );
    assert_eq!(
        mrpt_error("RAWSCAN 1.5 3 3.14 80 0.78 0 0 1 2 3 rightToLeft=yes\n"),
        "line 1: RAWSCAN field 12 (rightToLeft): expected rightToLeft=0 or rightToLeft=1, found 'rightToLeft=yes'"
    );
    assert_eq!(
        mrpt_error("ODOM 0 0 x 0 0 0 1.0\n"),
        "line 1: ODOM field 4 (theta): expected a finite number, found 'x'"
    );
}

#[test]
fn overlong_line_is_an_error_not_a_memory_hog() {
    let text = vec![b'1'; ekf_cli::import::MAX_LINE_BYTES + 10];
    let err = read_mrpt(text.as_slice())
        .find_map(Result::err)
        .expect("an error");
    assert!(
        matches!(err, ImportError::LineTooLong { line: 1, .. }),
        "{err}"
    );
}

/// Drains both importers over `bytes`; the test is that this returns.
fn drain(bytes: &[u8]) {
    let mut carmen = read_carmen(bytes, CarmenOptions::default());
    carmen.by_ref().for_each(drop);
    let _ = carmen.stats().span_ns();
    read_mrpt(bytes).for_each(drop);
}

const CARMEN: &str = include_str!("fixtures/carmen_corrected.log");
const MRPT: &str = include_str!("fixtures/mrpt_excerpt.txt");

/// One way to damage a line of a valid file.
#[derive(Debug, Clone)]
enum Mutation {
    DropField(usize),
    ReplaceField(usize, String),
    InsertField(usize, String),
    Truncate(usize),
    Duplicate,
}

fn mutation() -> impl Strategy<Value = Mutation> {
    let word = prop_oneof![
        Just("nan".to_owned()),
        Just("-1".to_owned()),
        Just("0".to_owned()),
        Just("1e308".to_owned()),
        Just("99999999999999999999".to_owned()),
        Just("rightToLeft=2".to_owned()),
        "[ -~]{0,8}",
    ];
    prop_oneof![
        (0..400usize).prop_map(Mutation::DropField),
        (0..400usize, word.clone()).prop_map(|(i, w)| Mutation::ReplaceField(i, w)),
        (0..400usize, word).prop_map(|(i, w)| Mutation::InsertField(i, w)),
        (0..4000usize).prop_map(Mutation::Truncate),
        Just(Mutation::Duplicate),
    ]
}

fn mutate(text: &str, line: usize, m: &Mutation) -> String {
    let mut lines: Vec<String> = text.lines().map(str::to_owned).collect();
    let i = line % lines.len();
    let mut words: Vec<String> = lines[i].split_whitespace().map(str::to_owned).collect();
    match m {
        Mutation::DropField(f) if !words.is_empty() => {
            let f = f % words.len();
            words.remove(f);
        }
        Mutation::ReplaceField(f, w) if !words.is_empty() => {
            let f = f % words.len();
            words[f].clone_from(w);
        }
        Mutation::InsertField(f, w) => words.insert(f % (words.len() + 1), w.clone()),
        Mutation::Truncate(n) => {
            let cut = lines[i]
                .char_indices()
                .nth(*n)
                .map_or(lines[i].len(), |(b, _)| b);
            words = vec![lines[i][..cut].to_owned()];
        }
        Mutation::Duplicate => lines.insert(i, lines[i].clone()),
        _ => {}
    }
    if !matches!(m, Mutation::Duplicate) {
        lines[i] = words.join(" ");
    }
    lines.join("\n")
}

proptest! {
    #[test]
    fn random_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..2048)) {
        drain(&bytes);
    }

    #[test]
    fn random_text_lines_never_panic(lines in proptest::collection::vec(
        prop_oneof![
            "(ODOM|FLASER|ROBOTLASER1|RAWSCAN|PARAM|NEFF|#)( [-0-9.e]{1,6}){0,40}",
            "[ -~]{0,60}",
        ],
        0..20,
    )) {
        drain(lines.join("\n").as_bytes());
    }

    #[test]
    fn mutated_valid_files_never_panic(
        mutations in proptest::collection::vec((0..20usize, mutation()), 1..4)
    ) {
        for original in [CARMEN, MRPT] {
            let mut text = original.to_owned();
            for (line, m) in &mutations {
                text = mutate(&text, *line, m);
            }
            drain(text.as_bytes());
        }
    }
}

#[test]
fn a_log_without_records_to_import_is_an_error_and_its_bag_is_finished() {
    use ekf_cli::commands::import::{import_log, LogFormat};
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("notes.log");
    std::fs::write(&input, "# a CARMEN header\nTRUEPOS 1 2 3\n# end\n").unwrap();
    let bag = dir.path().join("notes.mcap");
    let e = import_log(&input, &bag, LogFormat::Carmen(CarmenOptions::default())).unwrap_err();
    assert_eq!(
        e.to_string(),
        format!(
            "{}: nothing to import: no ODOM, FLASER or ROBOTLASER1 line (other record \
             types: 1, comments: 2, PARAM: 0, NEFF: 0)",
            input.display()
        )
    );
    let e = import_log(&input, &bag, LogFormat::Mrpt).unwrap_err();
    assert!(e.to_string().contains("no ODOM or RAWSCAN line"), "{e}");
    let written = ekf_cli::mcap_io::BagReader::open(&bag).unwrap();
    assert!(written.topics().is_empty());
}

#[test]
fn a_plain_log_standing_still_is_no_reset_and_a_repeated_odom_line_is_a_duplicate() {
    // The robot stands still: the ODOM after the scan repeats the pose of the one before
    // it, with a good stamp. That is odometry, not a GMapping reset.
    let text = "ODOM 1 2 0.5 0 0 0 1 h 1\n\
                FLASER 2 1.0 1.0 1 2 0.5 1 2 0.5 1.5 h 1.5\n\
                ODOM 1 2 0.5 0 0 0 2 h 2\n\
                ODOM 1 2 0.5 0 0 0 2 h 2\n";
    let mut reader = read_carmen(text.as_bytes(), CarmenOptions::default());
    let kinds: Vec<&str> = reader
        .by_ref()
        .map(|r| match r.unwrap() {
            ImportRecord::Odometry(_) => "odom",
            ImportRecord::Scan(_) => "scan",
            ImportRecord::Reference(_) => "ref",
            ImportRecord::Compass(_) => "compass",
        })
        .collect();
    assert_eq!(kinds, ["odom", "scan", "odom"]);
    let stats = reader.stats();
    assert_eq!(stats.odometry_resets, 0);
    assert_eq!(stats.duplicates.first_lines, [4]);
}
