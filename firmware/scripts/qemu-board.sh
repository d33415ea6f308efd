# Sourced by the scripts that start the QEMU firmware: the one definition of the emulated board
# (`tests/src/qemu.rs`, the end-to-end tests' launcher, passes the same arguments).
# shellcheck shell=bash
QEMU_BOARD=(qemu-system-arm -machine mps2-an386 -cpu cortex-m4 -display none -monitor none
    -semihosting-config enable=on,target=native)
