"""Errors are Python exceptions carrying `host`'s messages, its options named as this package's
keyword arguments; the calibration of a simulated session is near the simulator's truth (an
independent check, not the command line's output)."""

import subprocess
import tomllib  # Python ≥ 3.11 on the test machine; the package itself needs only 3.9

import numpy as np
import pytest

import accelcal
from conftest import UNIT_ID


def cli_error(host_bin, *args):
    p = subprocess.run([str(host_bin), *args], capture_output=True, text=True)
    assert p.returncode != 0
    # Notes (e.g. the time column's detected unit) may come first; the error is the rest.
    at = p.stderr.find("error: ")
    assert at == 0 or (at > 0 and p.stderr[at - 1] == "\n"), p.stderr
    return p.stderr[at + len("error: "):].strip()


def test_a_wrong_unit_raises_input_error_with_host_segments_message(hand, host_bin, tmp_path):
    expected = cli_error(
        host_bin, "segment", "--input", str(hand["csv"]), "--out", str(tmp_path / "s"),
        "--acc-unit", "g", "--gyro-unit", "deg/s", "--time-column", "t",
    )
    with pytest.raises(accelcal.InputError) as e:
        accelcal.segment_file(hand["csv"], acc_unit="g", gyro_unit="deg/s", time_column="t")
    # The same message, the option named as Python's keyword where the command line names its flag.
    assert "--acc-unit m/s2" in expected and "right --acc-unit" in expected
    in_python = expected.replace("--acc-unit m/s2", 'acc_unit="m/s2"').replace(
        "right --acc-unit", "right acc_unit")
    assert str(e.value) == in_python
    assert isinstance(e.value, accelcal.Error)


def test_a_still_recording_raises_calibration_error_with_host_segments_message(host_bin, tmp_path):
    # One position only: the coverage check refuses it.
    n = 4000
    rng = np.random.default_rng(1)
    acc = np.tile([0.0, 0.0, 9.80665], (n, 1)) + rng.normal(0, 0.01, (n, 3))
    gyro = rng.normal(0, 0.05, (n, 3))
    csv = tmp_path / "still.csv"
    t = np.arange(n) / 200.0
    rows = np.column_stack([t, acc, gyro])
    np.savetxt(csv, rows, delimiter=",", header="t,acc_x,acc_y,acc_z,gyr_x,gyr_y,gyr_z",
               comments="", fmt="%.17g")
    expected = cli_error(
        host_bin, "segment", "--input", str(csv), "--out", str(tmp_path / "s"),
        "--acc-unit", "m/s2", "--gyro-unit", "deg/s", "--time-column", "t",
    )
    with pytest.raises(accelcal.CalibrationError) as e:
        accelcal.segment(acc, gyro, t, acc_unit="m/s2", gyro_unit="deg/s")
    assert str(e.value) == expected


def test_bad_arguments_and_files_raise_the_right_kind(hand):
    hand_toml = hand["toml"]
    with pytest.raises(accelcal.InputError, match='acc_unit="furlong"'):
        accelcal.segment(np.zeros((10, 3)), np.zeros((10, 3)), rate_hz=100.0,
                         acc_unit="furlong", gyro_unit="deg/s")
    with pytest.raises(accelcal.InputError, match="shape"):
        accelcal.segment(np.zeros((10, 2)), np.zeros((10, 3)), rate_hz=100.0,
                         acc_unit="g", gyro_unit="deg/s")
    with pytest.raises(accelcal.FileError, match="no-such.toml"):
        accelcal.Calibration.load("no-such.toml")
    with pytest.raises(accelcal.InputError, match='format="nonsense": use one of kalibr'):
        accelcal.Calibration.load(hand_toml).export("nonsense")


def test_the_hand_calibration_is_near_the_simulators_truth(hand):
    truth = tomllib.loads(hand["truth"].read_text())
    cal = accelcal.calibrate(accelcal.segment_file(
        hand["csv"], acc_unit="m/s2", gyro_unit="deg/s", time_column="t", unit_id=UNIT_ID))
    # The gyro: the simulated scale (G's diagonal) and bias against the fitted ones, within 5σ. G's
    # off-diagonal entries are in the body frame of the session's own accelerometer calibration,
    # which the hand turns fix only up to the sensing axes' misalignment, not the simulator's frame.
    g, g_sigma = np.diag(cal.gyro_matrix), np.diag(cal.gyro_matrix_1sigma)
    true_g = np.diag(np.array(truth["gyro"]["matrix"]))
    assert np.all(np.abs(g - true_g) < 5 * g_sigma), (g, true_g, g_sigma)
    b, b_sigma = cal.gyro_bias_rad_s, cal.gyro_bias_rad_s_1sigma
    true_b = np.array(truth["gyro"]["bias_rad_s"])
    assert np.all(np.abs(b - true_b) < 5 * b_sigma), (b, true_b, b_sigma)
    # The accelerometer's zero biases and scale factors (m/s², m/s²/g) against the truth's.
    names = cal.names
    for key, true_key in [("bias", "zero_bias_m_s2"), ("scale", "scale_m_s2_per_g")]:
        k = [names.index(f"{key}_{a}") for a in "xyz"]
        value, sigma = cal.values[k], cal.sigmas[k]
        true = np.array(truth["static"][true_key])
        assert np.all(np.abs(value - true) < 5 * sigma), (key, value, true, sigma)


def test_a_temperature_column_and_a_memory_budget_read_as_host_segment_reads_them(
        hand, host_bin, tmp_path):
    # The hand-held CSV with the unit's temperature, a reading missing every 97th row.
    lines = hand["csv"].read_text().splitlines()
    out = [lines[0] + ",temp"]
    for i, line in enumerate(lines[1:]):
        out.append(line + ("," + ("nan" if i % 97 == 50 else f"{25.0 + i * 1e-4:.4f}")))
    csv = tmp_path / "hand-temp.csv"
    csv.write_text("\n".join(out) + "\n")
    reading = dict(acc_unit="m/s2", gyro_unit="deg/s", time_column="t", temp_column="temp")
    session = accelcal.segment_file(csv, max_samples=1_000_000, **reading)
    session.write(tmp_path / "py")
    run = subprocess.run(
        [str(host_bin), "-q", "segment", "--input", str(csv), "--out", str(tmp_path / "cli"),
         "--acc-unit", "m/s2", "--gyro-unit", "deg/s", "--time-column", "t",
         "--temp-column", "temp", "--max-samples", "1000000"],
        capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    py = (tmp_path / "py" / "samples.csv").read_text()
    assert py.splitlines()[0].endswith(",temp_c")
    assert py == (tmp_path / "cli" / "samples.csv").read_text()
    # Arrays are in memory already: a budget for reading a file is refused, and so is a column.
    d = np.loadtxt(hand["csv"], delimiter=",", skiprows=1)
    with pytest.raises(accelcal.Error, match="max_samples"):
        accelcal.segment(d[:, 1:4], d[:, 4:7], d[:, 0], acc_unit="m/s2", gyro_unit="deg/s",
                         max_samples=1000)
    with pytest.raises(accelcal.Error, match="temp_column"):
        accelcal.segment(d[:, 1:4], d[:, 4:7], d[:, 0], acc_unit="m/s2", gyro_unit="deg/s",
                         temp_column="temp")


def test_the_temperature_fit_chi2_per_axis_is_one_for_a_unit_that_fits(tmp_path):
    # A thermal ramp of the simulator's unit with white noise only: a right temperature model
    # leaves residuals of the noise's own size, χ²/dof = 1 within a few sqrt(2/dof) (dof ≈ 360 000).
    session = accelcal.simulate(tmp_path / "ramp", plan="thermal-ramp")
    per_axis = accelcal.calibrate(session).thermal_chi2_per_dof
    assert per_axis is not None and len(per_axis) == 3
    assert all(abs(c - 1.0) < 0.02 for c in per_axis), per_axis
    # No temperature model, no figure; nor for a calibration loaded from its file.
    plain = accelcal.calibrate(accelcal.simulate(tmp_path / "plain"))
    assert plain.thermal_chi2_per_dof is None
    plain.save(tmp_path / "cal")
    loaded = accelcal.Calibration.load(tmp_path / "cal" / "calibration.toml")
    assert loaded.thermal_chi2_per_dof is None
