"""Time and peak memory of `calibrate` from Python against `host calibrate` on the same session of
about 10⁶ rows (the oblique plan, each of its 24 segments shortened to 41.667 s at 1 kHz).

    cargo build --release -p host
    maturin build --release --manifest-path python/Cargo.toml --out dist
    pip install dist/accelcal-*.whl
    python python/bench/calibrate_1m.py [--host target/release/host] [--work DIR]

Each side runs once, in its own process under `/usr/bin/time -v` (wall clock, peak resident set):
the command line `host -q calibrate --input DIR --out-dir OUT`, and Python
`accelcal.calibrate(accelcal.load_session(DIR))` followed by `cal.save(OUT)` — both read the
session's samples.csv, fit, and write calibration.toml/.bin, which are checked to be identical.
The Python process's figure includes the interpreter and numpy (measured alone as the baseline).
"""

import argparse
import re
import subprocess
import sys
import tempfile
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
ROWS_PER_SEGMENT_S = 1e6 / 24 / 1000.0


def timed(cmd):
    """Runs cmd under /usr/bin/time -v: (wall s, peak RSS MB, stdout)."""
    p = subprocess.run(["/usr/bin/time", "-v", *cmd], capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"{' '.join(cmd)} failed:\n{p.stderr}")
    wall = re.search(r"Elapsed \(wall clock\) time.*: (?:(\d+):)?(\d+):([\d.]+)", p.stderr)
    h, m, s = wall.groups()
    seconds = int(h or 0) * 3600 + int(m) * 60 + float(s)
    rss_kb = int(re.search(r"Maximum resident set size \(kbytes\): (\d+)", p.stderr).group(1))
    return seconds, rss_kb / 1024.0, p.stdout


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--host", default=str(ROOT / "target" / "release" / "host"))
    ap.add_argument("--work", default=None, help="directory for the session (default: a temporary one)")
    a = ap.parse_args()
    work = Path(a.work or tempfile.mkdtemp(prefix="calibrate-1m-"))
    plan = (ROOT / "host" / "plans" / "oblique.toml").read_text()
    plan = re.sub(r"(?m)^duration_s = .*$", f"duration_s = {ROWS_PER_SEGMENT_S:.3f}", plan)
    (work / "plan-1m.toml").write_text(plan)
    session = work / "session"
    if not (session / "samples.csv").exists():
        subprocess.run([a.host, "-q", "simulate", "--plan", str(work / "plan-1m.toml"),
                        "--out", str(session), "--seed", "1"], check=True)
    rows = sum(1 for _ in open(session / "samples.csv")) - 1
    rate = tomllib.loads((session / "plan.toml").read_text())["sample_rate_hz"]

    cli_out, py_out = work / "cli", work / "py"
    cli = timed([a.host, "-q", "calibrate", "--input", str(session), "--out-dir", str(cli_out),
                 "--force"])
    script = (
        "import time, accelcal\n"
        "t0 = time.perf_counter()\n"
        f"s = accelcal.load_session({str(session)!r})\n"
        "t1 = time.perf_counter()\n"
        "cal = accelcal.calibrate(s)\n"
        "t2 = time.perf_counter()\n"
        f"cal.save({str(py_out)!r}, force=True)\n"
        "print(f'{t1 - t0:.3f} {t2 - t1:.3f}')\n"
    )
    py = timed([sys.executable, "-W", "ignore", "-c", script])
    base = timed([sys.executable, "-c", "import accelcal, numpy"])
    read_s, fit_s = map(float, py[2].split())
    same = (cli_out / "calibration.toml").read_bytes() == (py_out / "calibration.toml").read_bytes()
    print(f"session: {rows} rows at {rate:g} Hz ({(session / 'samples.csv').stat().st_size / 1e6:.0f} MB samples.csv), {session}")
    print(f"{'':38} {'wall s':>8} {'peak RSS MB':>12}")
    print(f"{'host -q calibrate --input (release)':38} {cli[0]:8.2f} {cli[1]:12.1f}")
    print(f"{'accelcal load_session + calibrate':38} {py[0]:8.2f} {py[1]:12.1f}")
    print(f"{'  of which load_session / calibrate':38} {read_s:4.2f}/{fit_s:.2f}")
    print(f"{'python -c import accelcal, numpy':38} {base[0]:8.2f} {base[1]:12.1f}")
    print(f"calibration.toml identical: {same}")


if __name__ == "__main__":
    main()
