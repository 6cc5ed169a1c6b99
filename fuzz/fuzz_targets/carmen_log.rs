//! CARMEN log text, read as `ekf import carmen` reads it (timestamp repair included).
#![no_main]

use ekf_cli::import::{read_carmen, CarmenOptions};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let mut reader = read_carmen(data, CarmenOptions::default());
    for record in reader.by_ref() {
        if record.is_err() {
            break;
        }
    }
    let _ = reader.stats();
});
