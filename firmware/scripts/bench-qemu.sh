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

elf="target/$target/release/qemu"
if command -v arm-none-eabi-size >/dev/null; then
    # Berkeley format: text (vector table + code + rodata), data, bss.
    read -r text data bss _ < <(arm-none-eabi-size "$elf" | tail -n1)
    flash=$((text + data))
    ram=$((data + bss))
    awk -v f="$flash" -v r="$ram" 'BEGIN { printf "size: QEMU firmware flash %d bytes (%.1f KiB; goal < 48 KiB), static RAM %d bytes (%.1f KiB; goal < 16 KiB)\n", f, f / 1024, r, r / 1024 }'
    echo "size: (static RAM excludes the stack; the stack high-water mark is printed by scripts/test.sh's on-target tests)"
else
    echo "size: arm-none-eabi-size not found (apt-get install binutils-arm-none-eabi)" >&2
    exit 1
fi
