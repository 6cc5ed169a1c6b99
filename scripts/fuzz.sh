#!/usr/bin/env bash
# Fuzzes every parser that takes bytes from outside (fuzz/fuzz_targets/, libFuzzer through
# cargo-fuzz) for SECONDS each, and prints how many inputs each ran.
#
#   scripts/fuzz.sh [SECONDS] [TARGET...]      default: 60 s, every target
#   EKF_FUZZ_SANITIZER=none scripts/fuzz.sh    without AddressSanitizer (see below)
#
# Installs what it needs: the nightly toolchain (libFuzzer needs its sanitizer support)
# and cargo-fuzz. Each target starts from its seeds (fuzz/seeds/TARGET, made from the
# test data by fuzz/make_seeds.py) and the corpus earlier runs left in fuzz/corpus/TARGET
# (not committed), and replays the inputs that once crashed it (fuzz/regressions/TARGET).
# A crash stops the run: libFuzzer prints the input it saved under fuzz/artifacts/TARGET/,
# which `cargo +nightly fuzz run TARGET FILE` replays. Copy it to fuzz/regressions/TARGET/
# and write a test next to the parser before fixing it.
set -euo pipefail
cd "$(dirname "$0")/.."

seconds=${1:-60}
if ! [[ "$seconds" =~ ^[0-9]+$ ]]; then
    echo "usage: scripts/fuzz.sh [SECONDS] [TARGET...] (SECONDS a whole number, got '$seconds')" >&2
    exit 2
fi
[ $# -gt 0 ] && shift

# The cargo-fuzz release this script was written against.
CARGO_FUZZ_VERSION=0.13.2

rustup toolchain list | grep -q '^nightly' ||
    rustup toolchain install nightly --profile minimal
if ! cargo fuzz --version 2>/dev/null | grep -q "$CARGO_FUZZ_VERSION"; then
    cargo install cargo-fuzz --locked --version "$CARGO_FUZZ_VERSION"
fi

if [ $# -gt 0 ]; then
    targets=("$@")
else
    list=$(cargo +nightly fuzz list)
    mapfile -t targets <<<"$list"
fi
if [ -z "${targets[*]}" ]; then
    echo "error: no fuzz targets found (cargo +nightly fuzz list printed nothing)" >&2
    exit 1
fi

# One build for all targets: release with debug assertions (so overflow is a crash too),
# instrumented by the sanitizer EKF_FUZZ_SANITIZER names (cargo-fuzz's: address, the
# default, leak, memory, thread or none). `run` gets the same flags, or it builds again.
sanitizer=${EKF_FUZZ_SANITIZER:-address}
build_flags=(--debug-assertions --sanitizer "$sanitizer")
cargo +nightly fuzz build "${build_flags[@]}"

for target in "${targets[@]}"; do
    corpus=fuzz/corpus/$target
    mkdir -p "$corpus"
    log=$(mktemp)
    status=0
    # -timeout: one input taking 10 s is a hang; -rss_limit_mb: a runaway allocation.
    # Inputs that once crashed the target (fuzz/regressions/TARGET) run first, every time.
    dirs=("$corpus" "fuzz/seeds/$target")
    [ -d "fuzz/regressions/$target" ] && dirs+=("fuzz/regressions/$target")
    cargo +nightly fuzz run "${build_flags[@]}" "$target" "${dirs[@]}" -- \
        -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
        >"$log" 2>&1 || status=$?
    runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
    printf '%-16s %10s runs in %ss\n' "$target" "${runs:-?}" "$seconds"
    if [ "$status" -ne 0 ]; then
        tail -40 "$log" >&2
        rm -f "$log"
        echo "error: fuzz target $target failed (exit status $status); see above" >&2
        exit 1
    fi
    rm -f "$log"
done
echo "fuzzing: ${#targets[@]} targets, ${seconds}s each, sanitizer $sanitizer, no crash"
