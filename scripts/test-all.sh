#!/usr/bin/env bash
# Runs every test of the project, installing what it needs (the Rust target, QEMU) when missing.
# This is the README's test command and exactly what .ci/run calls.
set -euo pipefail
cd "$(dirname "$0")/.."

step() { printf '\n==> %s\n' "$*"; }

# Test output is also kept in a log, so that the closing line can count every test that ran.
log=$(mktemp)
trap 'rm -f "$log"' EXIT
tests() { "$@" 2>&1 | tee -a "$log"; }

step "toolchain: thumbv7em-none-eabihf target, rustfmt, clippy"
rustup target add thumbv7em-none-eabihf >/dev/null
rustup component add rustfmt clippy >/dev/null

step "format"
cargo fmt --all -- --check
cargo fmt --manifest-path firmware/Cargo.toml --all -- --check

step "clippy (PC workspace)"
cargo clippy --workspace --all-targets -- -D warnings

step "documentation (PC workspace): every public item documented, every link resolved"
RUSTDOCFLAGS="-D warnings" cargo doc --no-deps --workspace

step "shared builds for the Cortex-M4F without std"
CARGO_TARGET_THUMBV7EM_NONE_EABIHF_RUSTFLAGS="-D warnings" \
  cargo build -p shared --no-default-features --target thumbv7em-none-eabihf

step "PC tests (shared, host, end-to-end)"
tests cargo test --workspace

step "firmware: PC tests of the device logic, both boards, QEMU on-target tests"
tests bash firmware/scripts/test.sh

step "end to end: host calibrate over the pty of the firmware running in QEMU"
tests cargo test -p e2e --test qemu_loop -- --ignored

count() {
  grep -E "^test result: |qemu-target-tests: " "$log" | grep -oE "[0-9]+ $1" | awk '{s += $1} END {print s + 0}'
}
echo
echo "every step passed (cargo test and the QEMU on-target tests, summed):"
echo "test-all: $(count passed) passed, $(count failed) failed"
