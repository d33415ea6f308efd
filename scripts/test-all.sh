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

step "system packages the tests need: arm-none-eabi-gcc, newlib and QEMU for the C package's Cortex-M4F run, script(1)"
packages=()
command -v arm-none-eabi-gcc >/dev/null || packages+=(gcc-arm-none-eabi)
# rdimon.specs (semihosting start-up and stdio) comes with newlib, not with the compiler.
dpkg -s libnewlib-arm-none-eabi >/dev/null 2>&1 || packages+=(libnewlib-arm-none-eabi)
command -v qemu-system-arm >/dev/null || packages+=(qemu-system-arm)
# The progress test gives `host` a terminal with script(1) (util-linux's, in bsdutils).
command -v script >/dev/null || packages+=(bsdutils)
# The Python package's tests run in a fresh virtual environment (Debian splits venv/ensurepip out).
python3 -c 'import ensurepip, venv' 2>/dev/null || packages+=(python3-venv)
# The live page's test (host/tests/live_view.rs) drives Debian's headless Chromium.
command -v chromium >/dev/null || packages+=(chromium)
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
tests cargo test --workspace --no-fail-fast

step "firmware: PC tests of the device logic, both boards, QEMU on-target tests"
tests bash firmware/scripts/test.sh

step "end to end: host calibrate over the pty of the firmware running in QEMU"
tests cargo test -p e2e --test qemu_loop -- --ignored

step "Python package: the wheel (maturin, dev profile) in a fresh virtual environment, pytest against host"
python3 -c 'import sys; sys.exit(0 if sys.version_info >= (3, 9) else 1)' ||
  { echo "python3 is $(python3 --version 2>&1): the package needs 3.9 or later" >&2; exit 1; }
cargo fmt --manifest-path python/Cargo.toml -- --check
cargo clippy --manifest-path python/Cargo.toml -- -D warnings
pyenv=$(mktemp -d)
trap 'rm -f "$log"; rm -rf "$pyenv"' EXIT
python3 -m venv "$pyenv/venv"
# Pinned: the build tool and the test's libraries, from PyPI.
"$pyenv/venv/bin/pip" install -q maturin==1.7.4 numpy==2.4.6 pandas==3.1.1 pytest==9.2.0
"$pyenv/venv/bin/maturin" build -q --manifest-path python/Cargo.toml --out "$pyenv/wheel"
# With the `[pandas]` extra, as the Python README installs it.
"$pyenv/venv/bin/pip" install -q "$(ls "$pyenv"/wheel/accelcal-*.whl)[pandas]"
# The tests run `host` (target/debug/host, built by the PC tests above) beside the package.
tests "$pyenv/venv/bin/python" -m pytest -q -p no:cacheprovider python/tests

count() {
  # pytest's closing line: "N passed in T s" (after "M failed, " when some failed).
  grep -E "^test result: |qemu-target-tests: |^([0-9]+ failed, )?[0-9]+ passed" "$log" |
    grep -oE "[0-9]+ $1" | awk '{s += $1} END {print s + 0}'
}
echo
echo "every step passed (cargo test, the QEMU on-target tests and pytest, summed):"
echo "test-all: $(count passed) passed, $(count failed) failed"
