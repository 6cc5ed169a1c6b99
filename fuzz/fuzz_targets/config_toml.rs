//! Configuration files: parsed and validated as `ekf --config` does. A configuration
//! that is accepted must build the filter it describes without a panic.
#![no_main]

use ekf_ros::config::Config;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let _ = Config::from_toml(text, "fuzz.toml");
});
