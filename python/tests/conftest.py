"""Shared fixtures: the `host` binary of this tree and one hand-held session run through the command
line (simulate-hand → segment → calibrate), which every equivalence test compares against."""

import json
import os
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
UNIT_ID = "0123456789abcdef01234567"


@pytest.fixture(scope="session")
def host_bin() -> Path:
    """`host` built from this tree (ACCELCAL_HOST overrides it)."""
    given = os.environ.get("ACCELCAL_HOST")
    if given:
        return Path(given)
    subprocess.run(["cargo", "build", "-q", "-p", "host"], cwd=ROOT, check=True)
    return target_dir() / "debug" / "host"


def target_dir() -> Path:
    """Where cargo builds this workspace: CARGO_TARGET_DIR (or a config's target-dir) when set,
    else target/, as `cargo metadata` says."""
    meta = subprocess.run(
        ["cargo", "metadata", "--format-version", "1", "--no-deps"],
        cwd=ROOT,
        check=True,
        capture_output=True,
        text=True,
    )
    return Path(json.loads(meta.stdout)["target_directory"])


def run(host_bin: Path, *args: str, cwd=None) -> subprocess.CompletedProcess:
    """Runs `host ARGS…`, failing the test with its stderr when it fails."""
    p = subprocess.run([str(host_bin), *args], capture_output=True, text=True, cwd=cwd)
    assert p.returncode == 0, f"host {' '.join(args)} failed ({p.returncode}):\n{p.stderr}"
    return p


@pytest.fixture(scope="session")
def hand(host_bin, tmp_path_factory):
    """The command line's hand-held session: hand.csv, the segmented session dir, and
    `host calibrate --input DIR --json`'s files and document."""
    d = tmp_path_factory.mktemp("cli")
    csv = d / "hand.csv"
    run(host_bin, "-q", "simulate-hand", "--out", str(csv), "--seed", "3")
    seg = d / "session"
    run(
        host_bin, "-q", "segment", "--input", str(csv), "--out", str(seg),
        "--acc-unit", "m/s2", "--gyro-unit", "deg/s", "--time-column", "t",
        "--unit-id", UNIT_ID,
    )
    doc = run(host_bin, "-q", "calibrate", "--input", str(seg), "--json").stdout
    return {
        "csv": csv,
        "truth": d / "hand.truth.toml",
        "session": seg,
        "summary": json.loads(doc),
        "toml": seg / "calibration.toml",
        "bin": seg / "calibration.bin",
    }


def unwritten(doc: dict) -> dict:
    """`host calibrate --json`'s document as `accelcal.calibrate` gives it: the same result, but no
    files written (`files` is None)."""
    return {**doc, "files": None}


def read_csv_exact(path: Path):
    """A CSV's header and rows, every number parsed by Python's float (exact for the shortest
    round-trip text `host` writes; pandas' default parser is not)."""
    lines = path.read_text().splitlines()
    header = lines[0].split(",")
    rows = [line.split(",") for line in lines[1:] if line and not line.startswith("#")]
    return header, rows


@pytest.fixture(scope="session")
def table(host_bin, tmp_path_factory):
    """The command line's session on the virtual rate table (the short-oblique plan: lever arms observable)
    and `host calibrate --input DIR --json`'s files and document."""
    d = tmp_path_factory.mktemp("table") / "cli"
    run(host_bin, "-q", "simulate", "--out", str(d), "--plan", "short-oblique", "--seed", "2")
    doc = run(host_bin, "-q", "calibrate", "--input", str(d), "--json").stdout
    return {"session": d, "summary": json.loads(doc), "toml": d / "calibration.toml"}
