#!/usr/bin/env bash
# Checks that two builds of `host` behave the same on the same inputs: a change that claims "behaviour
# unchanged" (a refactoring) is checked by running the binary before and after it.
#
#   scripts/check-same-output.sh OLD_HOST_BIN NEW_HOST_BIN
#
# Build the old binary from the commit before the change in a worktree of its own, e.g.
#   git worktree add /tmp/old <commit> && cargo build -p host --manifest-path /tmp/old/Cargo.toml
#   scripts/check-same-output.sh /tmp/old/target/debug/host target/debug/host
#
# For each case, both binaries simulate the same session (samples.csv, plan.toml and truth.toml must be
# byte-identical), then both calibrate the OLD binary's session with `calibrate --input`: the printed
# output (stdout and stderr, with the one timing line removed) and calibration.toml and calibration.bin
# must be byte-identical. The blob carries its creation time in whole seconds: with `faketime` installed
# (Debian package faketime) both calibrations run at the same frozen wall-clock time; without it they
# are run within the same second (retried until they are). `plan --check`, `export` and `compare` are
# compared too, and `segment` and `apply` on a simulated hand-held logger recording. Exits nonzero at
# the first difference, naming it.
#
# samples.csv, calibration.toml and calibration.bin are compared raw. Text meant for a person (printed
# output, truth.toml's comment, the export headers) is compared after applying the renames the
# restructuring made on purpose (RENAMES below: the model document's new path, x-io Fusion's current
# type name) to the OLD binary's text.
set -euo pipefail

if [ $# -ne 2 ]; then
  echo "usage: $0 OLD_HOST_BIN NEW_HOST_BIN" >&2
  exit 2
fi
old=$(realpath "$1")
new=$(realpath "$2")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

RENAMES='s#MODEL\.md#docs/model.md#g; s#FusionCalibrationInertial#FusionModelInertial#g'

# same_text OLD_FILE NEW_FILE WHAT: like `same`, after RENAMES on the old text.
same_text() {
  sed "$RENAMES" "$1" >"$1.renamed"
  same "$1.renamed" "$2" "$3"
}

same() { # same FILE_A FILE_B WHAT
  if ! cmp -s "$1" "$2"; then
    echo "DIFFERENT: $3" >&2
    diff "$1" "$2" | head -20 >&2 || true
    exit 1
  fi
  echo "same: $3"
}

# The reader's throughput line ("read N rows ... in 0.06 s") depends on the machine's speed.
untimed() { grep -v '^read [0-9]* rows' "$1" >"$1.untimed" || true; }

# Calibrates the session in $1 with both binaries into $2/old and $2/new, within one wall-clock second.
# as_passed OUT: a calibration that failed its checks is written as calibration.FAILED.toml/.bin
# and exits 3; both are in the printed output (compared), and its files are compared under the
# plain names.
as_passed() {
  local f
  for f in "$1"/old/calibration.FAILED.* "$1"/new/calibration.FAILED.*; do
    [ -e "$f" ] && mv "$f" "${f/.FAILED/}"
  done
  return 0
}

calibrate_both() {
  local session=$1 out=$2
  shift 2
  if command -v faketime >/dev/null; then
    rm -rf "$out"
    mkdir -p "$out"
    export FAKETIME_DONT_FAKE_MONOTONIC=1
    faketime -f '2026-01-01 00:00:00' "$old" calibrate --input "$session" --out-dir "$out/old" "$@" >"$out/old.out" 2>&1 ||
      echo "exit status $?" >>"$out/old.out"
    faketime -f '2026-01-01 00:00:00' "$new" calibrate --input "$session" --out-dir "$out/new" "$@" >"$out/new.out" 2>&1 ||
      echo "exit status $?" >>"$out/new.out"
    as_passed "$out"
    return 0
  fi
  for attempt in 1 2 3 4 5; do
    rm -rf "$out"
    mkdir -p "$out"
    local t0 t1
    t0=$(date +%s)
    "$old" calibrate --input "$session" --out-dir "$out/old" "$@" >"$out/old.out" 2>&1 ||
      echo "exit status $?" >>"$out/old.out"
    "$new" calibrate --input "$session" --out-dir "$out/new" "$@" >"$out/new.out" 2>&1 ||
      echo "exit status $?" >>"$out/new.out"
    t1=$(date +%s)
    if [ "$t0" = "$t1" ]; then
      as_passed "$out"
      return 0
    fi
    echo "(the two calibrations straddled a second; again, attempt $attempt)"
  done
  echo "could not run both calibrations within one second" >&2
  exit 1
}

case_no=0
check_case() { # check_case "SIMULATE ARGS" "CALIBRATE ARGS"
  case_no=$((case_no + 1))
  local dir=$work/case$case_no
  mkdir -p "$dir"
  # shellcheck disable=SC2086
  "$old" simulate -q --out "$dir/sim-old" $1 >"$dir/sim-old.out" 2>&1
  # shellcheck disable=SC2086
  "$new" simulate -q --out "$dir/sim-new" $1 >"$dir/sim-new.out" 2>&1
  for f in plan.toml samples.csv; do
    same "$dir/sim-old/$f" "$dir/sim-new/$f" "case $case_no simulate $1: $f"
  done
  same_text "$dir/sim-old/truth.toml" "$dir/sim-new/truth.toml" "case $case_no simulate $1: truth.toml"
  sed "s#$dir/sim-old#DIR#g" "$dir/sim-old.out" >"$dir/a"
  sed "s#$dir/sim-new#DIR#g" "$dir/sim-new.out" >"$dir/b"
  same_text "$dir/a" "$dir/b" "case $case_no simulate $1: printed output"
  # shellcheck disable=SC2086
  calibrate_both "$dir/sim-old" "$dir/cal" $2
  untimed "$dir/cal/old.out"
  untimed "$dir/cal/new.out"
  sed -i "s#$dir/cal/old#OUT#g" "$dir/cal/old.out.untimed"
  sed -i "s#$dir/cal/new#OUT#g" "$dir/cal/new.out.untimed"
  same_text "$dir/cal/old.out.untimed" "$dir/cal/new.out.untimed" "case $case_no calibrate $2: printed output"
  same "$dir/cal/old/calibration.toml" "$dir/cal/new/calibration.toml" "case $case_no calibrate $2: calibration.toml"
  same "$dir/cal/old/calibration.bin" "$dir/cal/new/calibration.bin" "case $case_no calibrate $2: calibration.bin"
  for format in plain fusion kalibr all; do
    # A refused export (Kalibr without --noise) is compared too: its message and its exit status.
    "$old" export --calibration "$dir/cal/old/calibration.toml" --format $format >"$dir/exp-old" 2>&1 ||
      echo "exit status $?" >>"$dir/exp-old"
    "$new" export --calibration "$dir/cal/old/calibration.toml" --format $format >"$dir/exp-new" 2>&1 ||
      echo "exit status $?" >>"$dir/exp-new"
    same_text "$dir/exp-old" "$dir/exp-new" "case $case_no export --format $format"
  done
  "$old" compare "$dir/sim-old/truth.toml" "$dir/cal/old/calibration.toml" >"$dir/cmp-old" 2>&1
  "$new" compare "$dir/sim-old/truth.toml" "$dir/cal/old/calibration.toml" >"$dir/cmp-new" 2>&1
  same_text "$dir/cmp-old" "$dir/cmp-new" "case $case_no compare truth calibration"
}

check_case "--plan short" ""
check_case "--plan paper --seed 7 --tilt-deg 0.01 --lsb 0.001" "--method paper"
check_case "--plan oblique --seed 3 --drift-mg-sqrt-s 0.01 --gyro-bias-deg-s 0.1,-0.2,0.05" "--reference centroid"
check_case "--plan quick-oblique --no-noise --noise-mg 0.5" ""

for plan in paper oblique short short-oblique quick-oblique; do
  "$old" plan --check "$plan" >"$work/plan-old" 2>&1
  "$new" plan --check "$plan" >"$work/plan-new" 2>&1
  same_text "$work/plan-old" "$work/plan-new" "plan --check $plan"
done

# `host segment` and `host apply` on a simulated hand-held logger recording (the readers, the
# segmentation, the hand-turn gyro fit, the device's compensation over a log).
hand=$work/hand
units="--time-column t --acc-unit m/s2 --gyro-unit deg/s"
mkdir -p "$hand"
"$old" simulate-hand --seed 4 --out "$hand/log" >/dev/null 2>&1
for bin in old new; do
  b=$old
  [ $bin = new ] && b=$new
  # shellcheck disable=SC2086
  "$b" segment --input "$hand/log" $units --out "$hand/seg-$bin" >"$hand/$bin.out" 2>&1
  # shellcheck disable=SC2086
  "$b" segment --input "$hand/log" $units --out "$hand/json-$bin" --json >"$hand/$bin.json" 2>/dev/null
  sed -i "s#$hand/seg-$bin#OUT#g" "$hand/$bin.out"
  sed -i "s#$hand/json-$bin#OUT#g" "$hand/$bin.json"
done
same_text "$hand/old.out" "$hand/new.out" "segment: printed output"
same_text "$hand/old.json" "$hand/new.json" "segment --json"
for f in plan.toml samples.csv gyro.toml; do
  same "$hand/seg-old/$f" "$hand/seg-new/$f" "segment: $f"
done
calibrate_both "$hand/seg-old" "$hand/cal"
same "$hand/cal/old/calibration.toml" "$hand/cal/new/calibration.toml" "segment, calibrate: calibration.toml"
for bin in old new; do
  b=$old
  [ $bin = new ] && b=$new
  # shellcheck disable=SC2086
  "$b" apply --input "$hand/log" $units --calibration "$hand/cal/old/calibration.toml" \
    --out "$hand/applied-$bin.csv" >"$hand/apply-$bin.out" 2>&1 || echo "exit status $?" >>"$hand/apply-$bin.out"
  sed -i "s#$hand/applied-$bin.csv#OUT#g" "$hand/apply-$bin.out"
done
same_text "$hand/apply-old.out" "$hand/apply-new.out" "apply: printed output"
same "$hand/applied-old.csv" "$hand/applied-new.csv" "apply: the compensated samples"

echo "check-same-output: old and new binaries print and write the same bytes"
