#!/usr/bin/env bash
# Regenerates docs/paper-reproduction.md's numbers and docs/figures/*.png: the paper's unit simulated
# on the paper's plan (1 mg white noise, seed 1), calibrated (joint least squares and the paper's
# eq. 24), the report written, the navigation figures printed. About a minute in release mode.
#
#   bash docs/reproduce.sh [OUT]        (OUT defaults to target/paper-reproduction)
#
# The session (900 000 rows, ~60 MB of CSV), the calibrations and the full report (PNG, SVG,
# report.html) stay in OUT; only the PNGs are copied to docs/figures/.
set -euo pipefail
cd "$(dirname "$0")/.."
out="${1:-target/paper-reproduction}"
cargo run --release -p host --example reproduce -- "$out" docs/figures
