//! Writes a ROS 2 bag with one message of every supported type, for checking that readers
//! we did not write (Python `mcap-ros2-support`, Foxglove, `ros2 bag info`) accept it.
//!
//! Usage: `cargo run -p ekf-cli --example write_sample_bag -- OUT.mcap`

mod sample;

use ekf_cli::mcap_io::BagWriter;
use std::process::ExitCode;

fn main() -> ExitCode {
    let Some(out) = std::env::args_os().nth(1) else {
        eprintln!("usage: write_sample_bag OUT.mcap");
        return ExitCode::from(2);
    };
    match write(&out) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("write_sample_bag: {e}");
            ExitCode::FAILURE
        }
    }
}

/// Writes every sample message, the `i`-th at [`sample::log_time`]`(i)`.
fn write(out: &std::ffi::OsStr) -> Result<(), ekf_cli::mcap_io::WriteError> {
    let mut writer = BagWriter::create(out)?;
    for (i, (topic, message)) in sample::messages().iter().enumerate() {
        writer.write_any(topic, sample::log_time(i), message)?;
    }
    writer.finish()
}
