#!/usr/bin/env bash
# Everything the firmware needs in CI, in order; stops at the first failure.
#
#  1. tools: the thumbv7em-none-eabihf target, qemu-system-arm and binutils-arm-none-eabi if missing
#  2. PC unit tests of the device-agnostic library (protocol, storage power cuts, stats, pipeline)
#  3. rustfmt --check, clippy -D warnings (library on the PC, every binary on the target) and the
#     library's rustdoc -D warnings
#  4. every board built with -D warnings (QEMU mps2-an386; the STM32F446 Nucleo and the STM32F405
#     flight controller, which only build here), their flash and RAM printed; the QEMU image's
#     flash budget (scripts/qemu-board.sh) and the F405's checked
#  5. on-target tests in QEMU (bit-exact compensation vs the PC, storage across a system reset)
#  6. end-to-end smoke test: the QEMU firmware over its serial pty (protocol, calibration, reset)
#  7. the benchmark (instruction counts, flash/RAM)
#
# Set SKIP_STM32=1 to skip the (slow to compile) STM32 builds, SKIP_BENCH=1 to skip step 7.
set -euo pipefail
cd "$(dirname "$0")/.."
# shellcheck source=qemu-board.sh
source scripts/qemu-board.sh
target=thumbv7em-none-eabihf
host=$(rustc -vV | sed -n 's/^host: //p')
# Where cargo builds (CARGO_TARGET_DIR when set).
tdir=$(firmware_target_dir)
step() { printf '\n=== firmware: %s\n' "$*"; }

# An STM32 image must leave the calibration store's sectors 1 and 2 (0x0800_4000..0x0800_C000,
# src/flash_layout.rs) alone: no loaded segment (by its load address) may touch them, or flashing
# the firmware would erase the calibration.
store_untouched() {
    local bad=0 type pa size
    while read -r type _ _ pa size _; do
        [ "$type" = LOAD ] && [ $((size)) -gt 0 ] || continue
        if [ $((pa)) -lt $((0x0800C000)) ] && [ $((pa + size)) -gt $((0x08004000)) ]; then
            echo "$1: a segment at $pa ($((size)) bytes) overlaps the calibration store" >&2
            bad=1
        fi
    done < <(arm-none-eabi-readelf -lW "$1")
    [ "$bad" = 0 ] && echo "$(basename "$1"): no segment in the calibration store's sectors 1-2"
}

# The DFU parts (scripts/dfu-images.sh) of an image are its flat binary without the store's gap:
# the vector table at its start, the code from 0xC000 on.
dfu_parts_match() {
    local dir
    dir=$(mktemp -d)
    scripts/dfu-images.sh "$1" "$dir" >/dev/null
    arm-none-eabi-objcopy -O binary "$1" "$dir/flat.bin"
    local name vectors
    name=$(basename "$1")
    vectors=$(stat -c%s "$dir/$name-sector0.bin")
    cmp -n "$vectors" "$dir/$name-sector0.bin" "$dir/flat.bin"
    tail -c +$((0xC000 + 1)) "$dir/flat.bin" | cmp - "$dir/$name-code.bin"
    echo "$name: the DFU parts are the image's bytes at 0x0800_0000 ($vectors) and 0x0800_C000"
    rm -r "$dir"
}

step "tools"
if ! rustup target list --installed | grep -qx "$target"; then
    rustup target add "$target"
fi
missing=()
command -v qemu-system-arm >/dev/null || missing+=(qemu-system-arm)
command -v arm-none-eabi-size >/dev/null || missing+=(binutils-arm-none-eabi)
if [ ${#missing[@]} -gt 0 ]; then
    sudo_cmd=()
    [ "$(id -u)" -ne 0 ] && sudo_cmd=(sudo)
    "${sudo_cmd[@]}" apt-get update
    "${sudo_cmd[@]}" apt-get install -y --no-install-recommends "${missing[@]}"
fi
qemu-system-arm --version | head -n1

step "PC unit tests of the device logic"
cargo test --lib --target "$host"

step "format and lints"
cargo fmt --check
cargo clippy --lib --tests --examples --target "$host" -- -D warnings
# The library's documentation: every link resolved (bit ranges such as \[7:0\] escaped).
RUSTDOCFLAGS="-D warnings" cargo doc --no-deps --lib --target "$host"

# -D warnings for the target builds. Not RUSTFLAGS (it would replace the link arguments of the root
# .cargo/config.toml): the target-scoped variable is merged with the config's array (checked with
# `cargo build -v`: both -Tlink.x and -D warnings reach rustc).
export CARGO_TARGET_THUMBV7EM_NONE_EABIHF_RUSTFLAGS="-D warnings"
qemu_features=(--no-default-features --features board-qemu)

step "build + clippy: QEMU board (mps2-an386)"
cargo clippy --release "${qemu_features[@]}" --bins --target "$target" -- -D warnings
cargo build --release "${qemu_features[@]}" --bins --target "$target"
qemu_size_check "$tdir/$target/release/qemu"

if [ "${SKIP_STM32:-0}" != 1 ]; then
    # One board at a time (each compiles the HAL for its own chip). Budgets of the F405 image:
    # flash <= 128 KiB (memory-f405.x leaves the code 208 KiB), static RAM <= 32 KiB.
    step "build + clippy: STM32F446 Nucleo-64 board"
    cargo clippy --release --features board-stm32f4 --bin stm32f4 --target "$target" -- -D warnings
    cargo build --release --features board-stm32f4 --bin stm32f4 --target "$target"
    arm-none-eabi-size "$tdir/$target/release/stm32f4"
    store_untouched "$tdir/$target/release/stm32f4"

    # The F405 boards, each from its description (`boards`): the SpeedyBee F405 V3 (`speedybee-v3`,
    # BMI270: the binary f405-bmi270), V5 (`speedybee-v5`) and V4 (no extra feature), both
    # ICM-42688-P (the binary f405); the V4 last, so that its image is the one left.
    for board in v3 v5 v4; do
        bin=f405 part=ICM-42688-P
        [ "$board" = v3 ] && bin=f405-bmi270 part=BMI270
        step "build + clippy: SpeedyBee F405 $board ($part, USB CDC-ACM)"
        f405_features=(--no-default-features --features board-f405)
        [ "$board" = v4 ] || f405_features=(--no-default-features --features "speedybee-$board")
        cargo clippy --release "${f405_features[@]}" --bin "$bin" --target "$target" -- -D warnings
        cargo build --release "${f405_features[@]}" --bin "$bin" --target "$target"
        arm-none-eabi-size "$tdir/$target/release/$bin"
        read -r text data bss _ < <(arm-none-eabi-size "$tdir/$target/release/$bin" | tail -n1)
        flash=$((text + data)) ram=$((data + bss))
        echo "F405 $board: flash $flash bytes (budget 131072), static RAM $ram bytes (budget 32768)"
        [ "$flash" -le 131072 ] && [ "$ram" -le 32768 ] || { echo "F405 over its budget" >&2; exit 1; }
        store_untouched "$tdir/$target/release/$bin"
    done
    dfu_parts_match "$tdir/$target/release/f405"
fi

step "on-target tests in QEMU"
timeout 120 "${QEMU_BOARD[@]}" -serial null -kernel "$tdir/$target/release/qemu-tests"

step "end-to-end over the serial pty"
cargo build --quiet --example pty_smoke --target "$host"
out=$(scripts/run-qemu.sh)
eval "$out"
trap 'kill "$QEMU_PID" 2>/dev/null || true' EXIT
timeout 120 "$tdir/$host/debug/examples/pty_smoke" "$QEMU_PTY"
kill "$QEMU_PID" 2>/dev/null || true
trap - EXIT

if [ "${SKIP_BENCH:-0}" != 1 ]; then
    step "benchmark"
    scripts/bench-qemu.sh
fi
printf '\n=== firmware: all steps passed\n'
