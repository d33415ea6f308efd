#!/usr/bin/env bash
# Builds the QEMU firmware and starts it on mps2-an386 with UART0 on a pseudo-terminal.
#
#   scripts/run-qemu.sh            start in the background; prints QEMU_PTY=... and QEMU_PID=...
#   scripts/run-qemu.sh --fg       same, then waits for QEMU (Ctrl-C stops it)
#   scripts/run-qemu.sh --icount   virtual time from the instruction count (see README)
#
# Logs: QEMU's stdout in $QEMU_RUN_DIR/qemu.out: its first line is QEMU's "char device redirected to
# /dev/pts/N", the rest the firmware's defmt frames (semihosting stdout); decode them with
# `tail -n +2 target/qemu-run/qemu.out | defmt-print -e target/thumbv7em-none-eabihf/release/qemu`
# (the build directory is $CARGO_TARGET_DIR instead of target/ when that is set).
# QEMU's errors go to $QEMU_RUN_DIR/qemu.log. QEMU discards UART output until the pty is opened and polls it about once
# a second: open the pty, send first, and allow >= 2 s for the first answer.
set -euo pipefail
cd "$(dirname "$0")/.."
# shellcheck source=qemu-board.sh
source scripts/qemu-board.sh

fg=0
icount=()
for arg in "$@"; do
    case "$arg" in
        --fg) fg=1 ;;
        --icount) icount=(-icount shift=0,align=off,sleep=off) ;;
        *) echo "unknown option $arg" >&2; exit 2 ;;
    esac
done

cargo build --quiet --release --no-default-features --features board-qemu --bin qemu \
    --target thumbv7em-none-eabihf
tdir=$(firmware_target_dir)
elf=$tdir/thumbv7em-none-eabihf/release/qemu
run_dir=${QEMU_RUN_DIR:-$tdir/qemu-run}
mkdir -p "$run_dir"
: >"$run_dir/qemu.out"

"${QEMU_BOARD[@]}" "${icount[@]}" -serial pty -kernel "$elf" >"$run_dir/qemu.out" 2>"$run_dir/qemu.log" &
pid=$!
echo "$pid" >"$run_dir/qemu.pid"

pty=""
for _ in $(seq 100); do
    pty=$(head -n1 "$run_dir/qemu.out" | grep -ao '/dev/pts/[0-9]*' || true)
    [ -n "$pty" ] && break
    if ! kill -0 "$pid" 2>/dev/null; then
        echo "QEMU exited:" >&2; cat "$run_dir/qemu.log" >&2; exit 1
    fi
    sleep 0.1
done
if [ -z "$pty" ]; then
    echo "no pty reported by QEMU" >&2; kill "$pid"; exit 1
fi
echo "QEMU_PTY=$pty"
echo "QEMU_PID=$pid"
if [ "$fg" = 1 ]; then
    trap 'kill "$pid" 2>/dev/null || true' INT TERM
    wait "$pid"
fi
