#!/usr/bin/env bash
# Instruction counts of the per-sample path in QEMU (-icount: SysTick counts instructions) and the
# flash/RAM use of the QEMU firmware image. Fails when a per-sample path is over its CPU share at the
# board's real rate (instructions as the proxy for cycles; checked in src/bin/qemu_bench.rs):
#   F405 IMU path, 8 kHz on 168 MHz:   <= 2 %   (420 instructions per sample), for each IMU:
#     the ICM-42688-P, the BMI270 and the LSM6DSO
#   Nucleo ADC path, 1 kHz on 180 MHz: <= 0.5 % (900 instructions per sample)
set -euo pipefail
cd "$(dirname "$0")/.."
# shellcheck source=qemu-board.sh
source scripts/qemu-board.sh
target=thumbv7em-none-eabihf
tdir=$(firmware_target_dir)
cargo build --quiet --release --no-default-features --features board-qemu \
    --bin qemu-bench --bin qemu --target "$target"
timeout 120 "${QEMU_BOARD[@]}" -icount shift=0,align=off,sleep=off \
    -serial null -kernel "$tdir/$target/release/qemu-bench"

qemu_size_check "$tdir/$target/release/qemu"
