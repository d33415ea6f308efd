#!/usr/bin/env bash
# Runs every test of the project, installing what it needs (the Rust target, QEMU, arm-none-eabi-gcc) when missing.
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

step "system packages the tests need: arm-none-eabi-gcc, newlib and QEMU for the C package's Cortex-M4F run"
packages=()
command -v arm-none-eabi-gcc >/dev/null || packages+=(gcc-arm-none-eabi)
# rdimon.specs (semihosting start-up and stdio) comes with newlib, not with the compiler.
dpkg -s libnewlib-arm-none-eabi >/dev/null 2>&1 || packages+=(libnewlib-arm-none-eabi)
command -v qemu-system-arm >/dev/null || packages+=(qemu-system-arm)
if [ ${#packages[@]} -gt 0 ]; then
  sudo_cmd=()
  [ "$(id -u)" -ne 0 ] && sudo_cmd=(sudo)
  "${sudo_cmd[@]}" apt-get update
  "${sudo_cmd[@]}" apt-get install -y --no-install-recommends "${packages[@]}"
fi

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
