//! MRPT text exports, read as `ekf import mrpt` reads them.
#![no_main]

use ekf_cli::import::read_mrpt;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let mut reader = read_mrpt(data);
    for record in reader.by_ref() {
        if record.is_err() {
            break;
        }
    }
    let _ = reader.stats();
});
