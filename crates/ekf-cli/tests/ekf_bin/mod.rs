//! Running the `ekf` binary under test.

use std::process::{Command, Output};

/// The `ekf` binary under test.
pub fn ekf() -> Command {
    Command::new(env!("CARGO_BIN_EXE_ekf"))
}

/// Runs `command`, which must succeed (else its stderr is shown), and returns its output.
pub fn run_ok(command: &mut Command) -> Output {
    let out = command.output().unwrap();
    assert!(
        out.status.success(),
        "{command:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// Runs `command`, which must fail, and returns its output.
pub fn run_fails(command: &mut Command) -> Output {
    let out = command.output().unwrap();
    assert!(!out.status.success(), "{command:?} succeeded");
    out
}
