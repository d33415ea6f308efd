#!/usr/bin/env bash
# Instruction counts of the per-sample path in QEMU (-icount: SysTick counts instructions) and the
# flash/RAM use of the QEMU firmware image.
set -euo pipefail
cd "$(dirname "$0")/.."
# shellcheck source=qemu-board.sh
source scripts/qemu-board.sh
target=thumbv7em-none-eabihf
cargo build --quiet --release --no-default-features --features board-qemu \
    --bin qemu-bench --bin qemu --target "$target"
timeout 120 "${QEMU_BOARD[@]}" -icount shift=0,align=off,sleep=off \
    -serial null -kernel "target/$target/release/qemu-bench"

qemu_size_check "target/$target/release/qemu"
