#!/usr/bin/env bash
# The project's one test command: installs what it needs, then runs every check.
# Used by CI (.ci/run) and by developers; see README.md.
set -euo pipefail
cd "$(dirname "$0")/.."

step() { printf '\n==> %s\n' "$*"; }

step "toolchain: rustfmt, clippy and the thumbv7em-none-eabihf target"
rustup component add rustfmt clippy >/dev/null
rustup target add thumbv7em-none-eabihf >/dev/null

step "cargo fmt --check"
cargo fmt --all --check

step "cargo clippy --all-targets -- -D warnings"
cargo clippy --workspace --all-targets -- -D warnings

step "cargo test (workspace)"
cargo test --workspace

step "no_std builds for thumbv7em-none-eabihf (ekf-core without alloc, lrf-lines with alloc)"
cargo build -p ekf-core -p lrf-lines --no-default-features --target thumbv7em-none-eabihf

step "cargo doc"
RUSTDOCFLAGS="-D warnings" cargo doc --workspace --no-deps
