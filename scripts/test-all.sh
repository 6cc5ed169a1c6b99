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

step "no import cycles between modules (scripts/module-cycles.py)"
"${PYTHON:-python3}" scripts/module-cycles.py

step "cargo clippy --all-targets -- -D warnings"
cargo clippy --workspace --all-targets -- -D warnings

step "cargo test (workspace)"
cargo test --workspace

step "no_std builds for thumbv7em-none-eabihf (ekf-core without alloc, lrf-lines and ekf-fusion with alloc)"
cargo build -p ekf-core -p lrf-lines -p ekf-fusion --no-default-features --target thumbv7em-none-eabihf

step "cargo doc"
RUSTDOCFLAGS="-D warnings" cargo doc --workspace --no-deps

# Every parser that takes outside bytes, fuzzed briefly (libFuzzer through cargo-fuzz, on
# nightly, both installed by the script); scripts/fuzz.sh SECONDS runs them longer.
# Without AddressSanitizer by default here: the workspace forbids unsafe code, and what
# these short runs catch (panics, overflows, hangs, runaway memory) libFuzzer catches
# without it. From a fresh target directory, the build with it (and full debug info) took
# 1,460 s of CPU, without it (and line tables only, fuzz/Cargo.toml) 894 s.
# scripts/fuzz.sh run alone keeps cargo-fuzz's default, address.
step "fuzz targets, ${EKF_FUZZ_SECONDS:=15}s each (scripts/fuzz.sh)"
EKF_FUZZ_SANITIZER=${EKF_FUZZ_SANITIZER:-none} scripts/fuzz.sh "$EKF_FUZZ_SECONDS"

# ---------------------------------------------------------------------------------------
# The real-log benchmark: every shared CARMEN log imported, mapped from its reference and
# replayed laser-only with the defaults, from the first reference pose and with --global;
# tests/corpus/check.py holds the bounds. The release binary, as users run it.
corpus_dir=""
for d in ../shared/data ../../shared/data; do
    [ -d "$d/carmen" ] && corpus_dir=$d && break
done
if [ -n "$corpus_dir" ]; then
    step "ekf corpus on $corpus_dir (release build)"
    cargo build --release -p ekf-cli --bin ekf
    corpus_out=$(mktemp -d)
    cargo run --release -q -p ekf-cli --bin ekf -- corpus "$corpus_dir/aces-corrected.log.gz" "$corpus_dir/carmen" \
        --work-dir "$corpus_out/tracked" --json >"$corpus_out/tracked.json"
    cargo run --release -q -p ekf-cli --bin ekf -- corpus "$corpus_dir/aces-corrected.log.gz" "$corpus_dir/carmen" \
        --work-dir "$corpus_out/global" --global --json >"$corpus_out/global.json"
    "${PYTHON:-python3}" tests/corpus/check.py "$corpus_out/tracked.json" "$corpus_out/global.json"
    rm -rf "$corpus_out"
elif [ "${EKF_REQUIRE_DATA:-0}" = 1 ]; then
    echo "error: shared/data/carmen not found beside the repository (EKF_REQUIRE_DATA=1)" >&2
    exit 1
else
    step "ekf corpus: skipped (no shared/data/carmen beside the repository)"
fi

# ---------------------------------------------------------------------------------------
# Python checks: readers we did not write (mcap, mcap-ros2-support, rosbags) decode what
# `ekf` writes, and the Python module ekf_loc agrees with FilterPy and with `ekf`. A venv
# at .venv is created on first use and reused; the pinned requirements are reinstalled
# only when tests/python/requirements.txt (or the interpreter) changes.
# PYTHON picks the interpreter (default python3). EKF_REQUIRE_DATA=1 turns the skip of the
# real-log tests (when ../shared/data is absent) into a failure.
py_started=$SECONDS
PYTHON=${PYTHON:-python3}
VENV=.venv
REQUIREMENTS=tests/python/requirements.txt

step "Python venv ($VENV) with $REQUIREMENTS"
if ! command -v "$PYTHON" >/dev/null; then
    echo "error: $PYTHON not found; install Python 3 (Debian: apt-get install python3 python3-venv)" >&2
    exit 1
fi
if ! "$PYTHON" -c 'import venv, ensurepip' 2>/dev/null; then
    echo "error: '$PYTHON -m venv' cannot work here: the ensurepip module is missing." >&2
    echo "       On Debian/Ubuntu install the python3-venv package:" >&2
    echo "       apt-get install python3-venv   (or python3.X-venv for your python3 version)" >&2
    exit 1
fi
# Reuse the venv only if its interpreter still runs with pip (a Python upgrade breaks it).
if [ -d "$VENV" ] && ! "$VENV/bin/python" -m pip --version >/dev/null 2>&1; then
    echo "$VENV is broken (interpreter or pip missing); recreating it"
    rm -rf "$VENV"
fi
if [ ! -d "$VENV" ]; then
    if ! "$PYTHON" -m venv "$VENV"; then
        rm -rf "$VENV"
        echo "error: '$PYTHON -m venv $VENV' failed (Debian/Ubuntu: apt-get install python3-venv)" >&2
        exit 1
    fi
fi
stamp="$VENV/.requirements.stamp"
want="$("$VENV/bin/python" -c 'import sys; print(sys.version)' | tr '\n' ' ') $(cksum <"$REQUIREMENTS")"
if [ "$(cat "$stamp" 2>/dev/null)" != "$want" ]; then
    rm -f "$stamp"
    PIP_DISABLE_PIP_VERSION_CHECK=1 PIP_NO_INPUT=1 \
        "$VENV/bin/python" -m pip install -q -r "$REQUIREMENTS"
    printf '%s' "$want" >"$stamp"
else
    echo "requirements unchanged; reusing $VENV"
fi
py_venv_done=$SECONDS

# The `ekf` binary and the example write_sample_bag that the Python checks run are the ones
# the cargo test stage built (target/debug). `cargo build -p ekf-cli` would compile much of
# the workspace again: without the dev-dependencies' features, several crates differ.
step "cargo test --workspace --no-run (the binary the Python checks run, already built)"
cargo test --workspace --no-run
target_dir=$(cargo metadata --no-deps --format-version 1 |
    "$VENV/bin/python" -c 'import json, sys; print(json.load(sys.stdin)["target_directory"])')
export EKF_BIN="$target_dir/debug/ekf"

# The Python module, built (debug profile, sharing the workspace's target directory) and
# installed into the venv as an editable package; `pip install ./crates/ekf-py` builds the
# same wheel in release mode for users.
step "maturin develop: build the Python module ekf_loc into $VENV"
VIRTUAL_ENV="$PWD/$VENV" "$VENV/bin/maturin" develop --quiet -m crates/ekf-py/Cargo.toml
py_build_done=$SECONDS

step "pytest tests/python"
pytest_status=0
"$VENV/bin/python" -m pytest tests/python -q || pytest_status=$?
if [ "$pytest_status" -eq 5 ]; then
    echo "error: pytest collected no tests in tests/python; the Python checks are gone" >&2
    exit 1
elif [ "$pytest_status" -ne 0 ]; then
    echo "error: pytest failed (exit status $pytest_status)" >&2
    exit "$pytest_status"
fi
py_done=$SECONDS
printf 'Python part: %ds (venv and requirements %ds, cargo build and maturin %ds, pytest %ds)\n' \
    $((py_done - py_started)) $((py_venv_done - py_started)) \
    $((py_build_done - py_venv_done)) $((py_done - py_build_done))
