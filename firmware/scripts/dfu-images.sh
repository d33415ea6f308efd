#!/usr/bin/env bash
# Writes an STM32 image (an ELF from `cargo build --release ... --bin f405`) as the two parts a
# DFU flash must write around the calibration store: the vector table for sector 0
# (0x0800_0000) and the code from sector 3 (0x0800_C000). A flat binary from 0x0800_0000 would
# also cover sectors 1 and 2, and DfuSe would erase the calibration there (src/flash_layout.rs).
#
#     scripts/dfu-images.sh target/thumbv7em-none-eabihf/release/f405 [OUTDIR]
#
# prints the two dfu-util commands that write them.
set -euo pipefail
elf=${1:?usage: dfu-images.sh ELF [OUTDIR]}
out=${2:-.}
name=$(basename "$elf")
vectors="$out/$name-sector0.bin"
code="$out/$name-code.bin"
# The layout's two addresses (src/flash_layout.rs: the flash's start, CODE_OFFSET).
vector_at=0x08000000
code_at=0x0800C000

# The image's loaded sections must start exactly there, or the parts would land elsewhere.
first=$(arm-none-eabi-objdump -h "$elf" | awk '$2 == ".vector_table" { print "0x" $5 }')
text=$(arm-none-eabi-objdump -h "$elf" | awk '$2 == ".text" { print "0x" $5 }')
if [ -z "$first" ] || [ $((first)) -ne $((vector_at)) ] || [ -z "$text" ] || [ $((text)) -ne $((code_at)) ]; then
    echo "dfu-images: $elf has its vector table at ${first:-none} and its code at ${text:-none}," \
        "not at $vector_at and $code_at: build it with this repository's memory layout" >&2
    exit 1
fi
arm-none-eabi-objcopy -O binary --only-section=.vector_table "$elf" "$vectors"
arm-none-eabi-objcopy -O binary --remove-section=.vector_table "$elf" "$code"
echo "wrote $vectors ($(stat -c%s "$vectors") bytes, at $vector_at) and $code ($(stat -c%s "$code") bytes, at $code_at)"
echo "flash them in the ST bootloader (the second one starts the firmware):"
echo "  dfu-util -a 0 -s $vector_at -D $vectors"
echo "  dfu-util -a 0 -s $code_at:leave -D $code"
