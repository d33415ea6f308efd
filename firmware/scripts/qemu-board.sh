# Sourced by the scripts that start the QEMU firmware: the one definition of the emulated board
# (`tests/src/qemu.rs`, the end-to-end tests' launcher, passes the same arguments).
# shellcheck shell=bash
QEMU_BOARD=(qemu-system-arm -machine mps2-an386 -cpu cortex-m4 -display none -monitor none
    -semihosting-config enable=on,target=native)

# The firmware workspace's build directory, as cargo places it: CARGO_TARGET_DIR (or a config's
# build.target-dir) when set, else firmware/target. Run from firmware/.
firmware_target_dir() {
    local dir
    dir=$(cargo metadata --format-version 1 --no-deps |
        sed -n 's/.*"target_directory":"\([^"]*\)".*/\1/p')
    if [ -z "$dir" ]; then
        echo "cargo metadata names no target_directory" >&2
        return 1
    fi
    echo "$dir"
}

# Flash budget of the QEMU firmware image, bytes: it fails above this. 48 KiB, the goal: the image
# is 48 932 bytes; README "Measured figures" says what each cut saved and what grew it.
QEMU_FLASH_BUDGET=49152

# Prints the QEMU firmware's flash and static RAM (arm-none-eabi-size: flash = text + data, static
# RAM = data + bss) and fails when the flash is over QEMU_FLASH_BUDGET.
qemu_size_check() {
    local elf=$1 text data bss flash ram
    if ! command -v arm-none-eabi-size >/dev/null; then
        echo "size: arm-none-eabi-size not found (apt-get install binutils-arm-none-eabi)" >&2
        return 1
    fi
    # Berkeley format: text (vector table + code + rodata), data, bss.
    read -r text data bss _ < <(arm-none-eabi-size "$elf" | tail -n1)
    flash=$((text + data))
    ram=$((data + bss))
    awk -v f="$flash" -v r="$ram" -v b="$QEMU_FLASH_BUDGET" 'BEGIN { printf "size: QEMU firmware flash %d bytes (%.1f KiB; budget %d bytes, %.1f KiB), static RAM %d bytes (%.1f KiB; goal < 16 KiB)\n", f, f / 1024, b, b / 1024, r, r / 1024 }'
    echo "size: (static RAM excludes the stack; the stack high-water mark is printed by scripts/test.sh's on-target tests)"
    if [ "$flash" -gt "$QEMU_FLASH_BUDGET" ]; then
        echo "size: QEMU firmware flash $flash bytes is over its budget of $QEMU_FLASH_BUDGET" >&2
        return 1
    fi
}
