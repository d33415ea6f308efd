#!/usr/bin/env bash
# The PC crates' dependency graph (workspace crates only) and each crate's public surface: the
# number of `pub` items (functions, types, constants, modules, re-exports, and `pub` methods and
# fields) in its non-test sources. Cargo refuses a cycle; an upward arrow would show here as a
# lower crate depending on a higher one (ARCHITECTURE.md, "Code map").
set -euo pipefail
cd "$(dirname "$0")/.."

echo "crate graph (workspace crates; an arrow is 'depends on'):"
cargo metadata --format-version 1 --no-deps 2>/dev/null | python3 -c '
import json, sys
m = json.load(sys.stdin)
names = {p["name"] for p in m["packages"]}
for p in m["packages"]:
    deps = sorted({d["rename"] or d["name"] for d in p["dependencies"] if d["name"] in names and d["kind"] is None})
    dev = sorted({d["name"] for d in p["dependencies"] if d["name"] in names and d["kind"] == "dev"} - set(deps))
    line = "  %-10s -> %s" % (p["name"], ", ".join(deps) or "(none)")
    if dev:
        line += "   (tests also: %s)" % ", ".join(dev)
    print(line)
'

echo
echo "public items per crate (non-test sources; pub, not pub(crate)):"
for krate in shared recording estimator outputs app device host; do
  n=$(find "$krate/src" -name '*.rs' ! -name '*tests*.rs' -print0 |
    xargs -0 awk 'FNR == 1 { skip = 0 } /^#\[cfg\(test\)\]/ { t = 1; next } t && /^(pub(\(crate\))? )?mod [a-z_]+ \{/ { skip = 1 } { t = 0 } !skip && /^[[:space:]]*pub (fn|struct|enum|const|static|mod|use|trait|type|unsafe fn|async fn)[[:space:]]|^[[:space:]]*pub [a-z_0-9]+:/ { n++ } END { print n + 0 }' |
    awk '{ s += $1 } END { print s }')
  printf '  %-10s %5d\n' "$krate" "$n"
done

echo
python3 scripts/house-counts.py
