//! TUM trajectory files (`ekf evaluate`, `ekf compare`, `ekf map plot`). A trajectory
//! that reads must write out as TUM that reads back to the same rows.
#![no_main]

use ekf_ros::tum::{read_tum, write_tum};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(trajectory) = read_tum(data, "fuzz.tum") else {
        return;
    };
    let mut written = Vec::new();
    write_tum(&mut written, &trajectory).expect("writing to memory");
    let again = read_tum(written.as_slice(), "written.tum").expect("written TUM reads back");
    assert_eq!(again.samples.len(), trajectory.samples.len());
});
