"""Each function of accelcal against the `host` command on the same data: the same numbers to the
last digit `host` prints, the same files byte for byte."""

import json
import subprocess

import numpy as np
import pandas as pd
import pytest

import accelcal
from conftest import ROOT, UNIT_ID, read_csv_exact, run, unwritten


def frame_exact(path):
    """The logger's CSV as a DataFrame, every number parsed exactly (Python's float)."""
    header, rows = read_csv_exact(path)
    return pd.DataFrame([[float(v) for v in r] for r in rows], columns=header)


@pytest.fixture(scope="module")
def py_session(hand):
    return accelcal.segment(
        frame_exact(hand["csv"]), acc_unit="m/s2", gyro_unit="deg/s", unit_id=UNIT_ID
    )


@pytest.fixture(scope="module")
def py_cal(py_session):
    return accelcal.calibrate(py_session)


def test_simulate_hand_gives_the_rows_of_host_simulate_hand(hand):
    d = accelcal.simulate_hand(seed=3)
    header, rows = read_csv_exact(hand["csv"])
    assert header == ["t", "acc_x", "acc_y", "acc_z", "gyr_x", "gyr_y", "gyr_z"]
    cli = np.array([[float(v) for v in r] for r in rows])
    assert cli.shape[0] == d["t"].shape[0]
    np.testing.assert_array_equal(d["t"], cli[:, 0])
    np.testing.assert_array_equal(d["acc"], cli[:, 1:4])
    np.testing.assert_array_equal(d["gyro"], cli[:, 4:7])
    assert d["truth_toml"] == hand["truth"].read_text()


def test_segment_of_a_dataframe_writes_host_segments_session(hand, py_session, tmp_path):
    assert py_session.plan_toml() == (hand["session"] / "plan.toml").read_text()
    py_session.write(tmp_path / "s")
    for name in ["plan.toml", "samples.csv", "gyro.toml"]:
        assert (tmp_path / "s" / name).read_bytes() == (hand["session"] / name).read_bytes(), name


def test_calibrate_gives_host_calibrates_files_and_document(hand, py_cal):
    assert py_cal.to_toml().encode() == hand["toml"].read_bytes()
    stamp = accelcal.Calibration.load(hand["bin"]).created_unix_s
    assert py_cal.to_blob(created_unix_s=stamp) == hand["bin"].read_bytes()
    assert py_cal.summary == unwritten(hand["summary"])


def test_calibration_arrays_are_the_documents_parameters(hand, py_cal):
    params = hand["summary"]["parameters"]
    assert py_cal.names == [p["name"] for p in params]
    np.testing.assert_array_equal(py_cal.values, [p["value"] for p in params])
    sig = [np.nan if p["sigma"] is None else p["sigma"] for p in params]
    np.testing.assert_array_equal(py_cal.sigmas, sig)
    assert py_cal.chi2 == hand["summary"]["chi2"] and py_cal.dof == hand["summary"]["dof"]
    g = hand["summary"]["calibration"]["gyro"]
    np.testing.assert_array_equal(py_cal.gyro_matrix, g["matrix"])
    np.testing.assert_array_equal(py_cal.gyro_bias_rad_s, g["bias_rad_s"])
    assert py_cal.warnings == hand["summary"]["warnings"]


def test_a_loaded_calibration_lists_the_parameters_the_estimated_one_does(hand, py_cal):
    # The hand-held session's calibration has a gyro: 24 paper-form values and the gyro's 12, named,
    # valued and in units alike whether estimated here or loaded from host's calibration.toml.
    loaded = accelcal.Calibration.load(hand["toml"])
    assert len(py_cal.names) == 36
    assert loaded.names == py_cal.names
    assert loaded.units == py_cal.units
    np.testing.assert_allclose(loaded.values, py_cal.values, rtol=1e-12, atol=0)
    # The sections' 1σ are the file's; the paper-form values' need the fit's covariance.
    np.testing.assert_array_equal(loaded.sigmas[24:], py_cal.sigmas[24:])
    assert np.isnan(loaded.sigmas[:24]).all()


def test_segment_file_and_arrays_give_the_same_calibration(hand, py_cal):
    from_file = accelcal.segment_file(
        hand["csv"], acc_unit="m/s2", gyro_unit="deg/s", time_column="t", unit_id=UNIT_ID
    )
    assert accelcal.calibrate(from_file).to_toml() == py_cal.to_toml()
    d = accelcal.simulate_hand(seed=3)
    arrays = accelcal.segment(
        d["acc"], d["gyro"], d["t"], acc_unit="m/s2", gyro_unit="deg/s", unit_id=UNIT_ID
    )
    assert accelcal.calibrate(arrays).to_toml() == py_cal.to_toml()


def test_load_and_simulate_give_host_calibrate_of_a_table_session(table, tmp_path):
    cli_dir = table["session"]
    with pytest.warns(UserWarning, match="no unit_id"):
        py = accelcal.simulate(tmp_path / "py", plan="short-oblique", seed=2)
        for name in ["plan.toml", "samples.csv"]:
            assert (tmp_path / "py" / name).read_bytes() == (cli_dir / name).read_bytes(), name
        for session in [py, accelcal.load_session(cli_dir)]:
            cal = accelcal.calibrate(session)
            assert cal.to_toml().encode() == table["toml"].read_bytes()
            assert cal.summary == unwritten(table["summary"])


def test_single_package_gives_host_calibrate_single_package(host_bin, tmp_path):
    # A one-package unit on a plan that does not say so: only the option ties the lever arms.
    session = tmp_path / "session"
    unit = ROOT / "host" / "units" / "single-package.toml"
    run(host_bin, "-q", "simulate", "--out", str(session), "--plan", "short-oblique",
        "--unit", str(unit), "--seed", "5")
    doc = json.loads(run(host_bin, "-q", "calibrate", "--input", str(session), "--single-package",
                         "--json").stdout)
    with pytest.warns(UserWarning, match="no unit_id"):
        tied = accelcal.calibrate(accelcal.load_session(session), single_package=True)
    assert tied.to_toml().encode() == (session / "calibration.toml").read_bytes()
    assert tied.summary == unwritten(doc)
    with pytest.warns(UserWarning, match="no unit_id"):
        free = accelcal.calibrate(accelcal.load_session(session))
    assert free.to_toml() != tied.to_toml()


def test_live_input_batch_and_python_calibrations_are_one_document(host_bin, tmp_path):
    # The live procedure on the simulated device, then the recording it saved through
    # `calibrate --input`, `host batch` and `accelcal.calibrate`: one calibrate use case, one
    # document (where each wrote its files and the live run's verification aside).
    live = json.loads(run(host_bin, "-q", "calibrate", "--port", "sim", "--plan", "quick-oblique",
                          "--out-dir", str(tmp_path / "live"), "--json").stdout)
    recording = tmp_path / "live" / "recording"
    given = json.loads(run(host_bin, "-q", "calibrate", "--input", str(recording), "--out-dir",
                           str(tmp_path / "input"), "--json").stdout)
    lot = tmp_path / "lot" / "u1"
    lot.mkdir(parents=True)
    for name in ["plan.toml", "samples.csv"]:
        (lot / name).write_bytes((recording / name).read_bytes())
    batch = json.loads(run(host_bin, "-q", "batch", "--input", str(tmp_path / "lot"), "--out",
                           str(tmp_path / "res"), "--json").stdout)["units"][0]["summary"]
    py = accelcal.calibrate(accelcal.load_session(recording)).summary
    assert live["verification"]["passed"] is True
    assert given["verification"] is None and py["verification"] is None
    assert py["files"] is None

    def calibration_part(doc):
        return {k: v for k, v in doc.items() if k not in ("files", "verification")}

    assert len(py["parameters"]) == 36
    assert calibration_part(py) == calibration_part(given)
    assert calibration_part(live) == calibration_part(given)
    assert calibration_part(batch) == calibration_part(given)
    assert set(py) == set(live) == set(given) == set(batch)


EXPORTS = [
    ("json", []),
    ("plain", []),
    ("fusion", []),
    ("all", []),
    ("kalibr-intrinsics", []),
    ("fusion-c", []),
    ("px4", ["--device-id", "1310988", "--gyro-device-id", "2490378"]),
    ("ardupilot", ["--device-id", "3932170", "--gyro-device-id", "3932426"]),
]


@pytest.mark.parametrize("fmt,flags", EXPORTS, ids=[e[0] for e in EXPORTS])
def test_export_writes_host_exports_text(hand, py_cal, host_bin, fmt, flags):
    cli = run(host_bin, "-q", "export", "--calibration", str(hand["toml"]), "--format", fmt, *flags)
    options = {}
    if flags:
        options = {"device_id": int(flags[1]), "gyro_device_id": int(flags[3])}
    assert py_cal.export(fmt, **options) == cli.stdout
    loaded = accelcal.Calibration.load(hand["toml"])
    assert loaded.export(fmt, **options) == cli.stdout


def test_export_c_header_writes_host_exports_package(hand, py_cal, host_bin, tmp_path):
    run(host_bin, "-q", "export", "--calibration", str(hand["toml"]), "--format", "c",
        "--out", str(tmp_path))
    files = py_cal.export("c")
    assert sorted(files) == sorted(p.name for p in tmp_path.iterdir())
    for name, text in files.items():
        assert text.encode() == (tmp_path / name).read_bytes(), name


def session_rows(session_dir):
    """samples.csv of a session as {segment: (t, u (n,3), w (n,3))}, parsed exactly."""
    _, rows = read_csv_exact(session_dir / "samples.csv")
    out = {}
    for r in rows:
        out.setdefault(r[0], []).append([float(v) for v in r[1:8]])
    return {k: np.array(v) for k, v in out.items()}


# The hand calibration has no lever arms: host refuses --lever there (it would change nothing), so
# its case runs both sides on their defaults (the full compensation).
@pytest.mark.parametrize("which,lever", [("hand", None), ("table", "full"), ("table", "rate")])
def test_apply_gives_host_applys_output(request, host_bin, which, lever):
    cli_session = request.getfixturevalue(which)
    session, toml = cli_session["session"], cli_session["toml"]
    lever_args = [] if lever is None else ["--lever", lever]
    cli = run(host_bin, "-q", "apply", "--input", str(session), "--calibration", str(toml),
              *lever_args)
    lever = lever or "full"
    lines = cli.stdout.splitlines()
    assert lines[0] == "segment,t_s,f_x_g,f_y_g,f_z_g,w_x_rad_s,w_y_rad_s,w_z_rad_s"
    expected, expected_w = {}, {}
    for line in lines[1:]:
        f = line.split(",")
        expected.setdefault(f[0], []).append([float(v) for v in f[2:5]])
        expected_w.setdefault(f[0], []).append([float(v) for v in f[5:8]])
    cal = accelcal.Calibration.load(toml)
    rate = accelcal.load_session(session).rate_hz
    segments = session_rows(session)
    assert list(segments) == list(expected)
    for name, rows in segments.items():
        # host apply restarts the ω̇ estimate at each segment: one call per segment does the same.
        f, w = accelcal.apply(cal, rows[:, 1:4], rows[:, 4:7], rate_hz=rate, lever=lever,
                              with_rate=True)
        np.testing.assert_array_equal(f, np.array(expected[name]), err_msg=name)
        np.testing.assert_array_equal(w, np.array(expected_w[name]), err_msg=name)


def test_allan_gives_host_noises_curves_and_terms(hand, host_bin):
    doc = json.loads(run(host_bin, "-q", "noise", "--input", str(hand["session"]), "--json").stdout)
    rows = session_rows(hand["session"])[doc["segment"]]
    assert rows.shape[0] == doc["samples"]
    terms = {"white_density": "white_density", "bias_instability": "bias_instability",
             "random_walk": "random_walk"}
    for j, axis in enumerate(doc["axes"]):
        a = accelcal.allan(rows[:, 1 + j], doc["sample_rate_hz"])
        assert a["tau_s"].tolist() == [p["tau_s"] for p in axis["points"]], axis["axis"]
        assert a["adev"].tolist() == [p["adev"] for p in axis["points"]], axis["axis"]
        assert a["terms"].tolist() == [p["terms"] for p in axis["points"]], axis["axis"]
        for k, key in enumerate(terms):
            assert a[key]["value"] == axis["terms"][key], (axis["axis"], key)
            assert a[key]["sigma"] == axis["terms"]["fits"][k]["sigma"], (axis["axis"], key)
            assert a[key]["upper_bound_2sigma"] == axis["terms"]["fits"][k]["upper_bound_2sigma"]
        assert np.all(a["adev_low"] < a["adev"]) and np.all(a["adev"] < a["adev_high"])


@pytest.mark.parametrize("name", ["hand.ulg", "hand.bin", "hand.mcap"])
def test_segment_file_reads_every_log_format_as_host_segment(host_bin, tmp_path, name):
    """A PX4 ULog, an ArduPilot DataFlash log and a ROS 2 bag (the reference tools' files of the
    host's log tests) cut into the session `host segment` writes, byte for byte."""
    log = ROOT / "recording" / "tests" / "fixtures" / "logs" / name
    run(host_bin, "-q", "segment", "--input", str(log), "--out", str(tmp_path / "cli"))
    session = accelcal.segment_file(log)
    session.write(tmp_path / "py")
    for f in ["plan.toml", "samples.csv", "gyro.toml"]:
        cli = tmp_path / "cli" / f
        assert cli.exists() == (tmp_path / "py" / f).exists(), f
        if cli.exists():
            assert (tmp_path / "py" / f).read_bytes() == cli.read_bytes(), f


def test_segment_of_raw_count_arrays_writes_host_segments_session(host_bin, tmp_path):
    # A 16-bit logger's raw counts: the accelerometer at mid-scale 32768, the gyro in counts.
    csv = tmp_path / "counts.csv"
    run(host_bin, "-q", "simulate-hand", "--out", str(csv), "--seed", "4", "--acc-unit", "LSB",
        "--acc-offset", "32768", "--gyro-unit", "LSB", "--gyro-lsb-per-dps", "16.4")
    cli = tmp_path / "cli"
    run(host_bin, "-q", "segment", "--input", str(csv), "--out", str(cli), "--time-column", "t",
        "--acc-unit", "LSB", "--acc-offset", "32768", "--gyro-unit", "LSB",
        "--gyro-lsb-per-dps", "16.4")
    header, rows = read_csv_exact(csv)
    data = np.array([[float(v) for v in r] for r in rows])
    s = accelcal.segment(data[:, 1:4], data[:, 4:7], data[:, 0], acc_unit="LSB",
                         acc_offset=[32768.0], gyro_unit="LSB", gyro_lsb_per_dps=16.4)
    s.write(tmp_path / "py")
    for name in ["plan.toml", "samples.csv", "gyro.toml"]:
        assert (tmp_path / "py" / name).read_bytes() == (cli / name).read_bytes(), name
    # Without the offset the arrays are refused with host's hint that names it.
    with pytest.raises(accelcal.InputError, match="32768"):
        accelcal.segment(data[:, 1:4], data[:, 4:7], data[:, 0], acc_unit="LSB",
                         gyro_unit="LSB", gyro_lsb_per_dps=16.4)


@pytest.fixture(scope="module")
def faces_noise(host_bin, tmp_path_factory):
    """A six-face session (still on a table: no tremor, so both sensors' N is determined), its
    samples and `host noise --out`'s noise.json and document."""
    d = tmp_path_factory.mktemp("faces")
    run(host_bin, "-q", "simulate-hand", "--six-faces", "--out", str(d / "six.csv"), "--seed", "3")
    run(host_bin, "-q", "segment", "--input", str(d / "six.csv"), "--out", str(d / "session"),
        "--acc-unit", "m/s2", "--gyro-unit", "deg/s", "--time-column", "t", "--unit-id", UNIT_ID)
    run(host_bin, "-q", "noise", "--input", str(d / "session"), "--out", str(d / "noise"))
    doc = json.loads((d / "noise" / "noise.json").read_text())
    rows = session_rows(d / "session")[doc["segment"]]
    assert rows.shape[0] == doc["samples"]
    return {"json": d / "noise" / "noise.json", "doc": doc, "rows": rows}


def test_export_takes_allans_result_as_host_noises_file(hand, py_cal, host_bin, faces_noise):
    """Kalibr's export from allan() of the six still signals host noise analyses is the one from
    its noise.json, in Python and from `host export --noise`: here a refusal naming the same
    undetermined figure (seconds of stillness do not determine a random walk)."""
    doc, rows = faces_noise["doc"], faces_noise["rows"]
    # The session is in m/s² and rad/s: host noise's six axes, as columns in its order.
    assert [a["axis"] for a in doc["axes"]] == ["accel_x", "accel_y", "accel_z",
                                                "gyro_x", "gyro_y", "gyro_z"]
    curves = accelcal.allan(rows[:, 1:7], doc["sample_rate_hz"])
    # The figures Kalibr gets are each sensor's worst axis of the curves' own terms.
    assert doc["kalibr"]["accelerometer_noise_density"] is not None
    assert doc["kalibr"]["gyroscope_noise_density"] is not None
    assert max(t["value"] for t in curves["white_density"][:3]) == \
        doc["kalibr"]["accelerometer_noise_density"]
    assert max(t["value"] for t in curves["white_density"][3:]) == \
        doc["kalibr"]["gyroscope_noise_density"]
    messages = []
    for noise in [curves, faces_noise["json"], str(faces_noise["json"])]:
        with pytest.raises(accelcal.CalibrationError) as e:
            py_cal.export("kalibr", noise=noise)
        messages.append(str(e.value))
    assert messages[0] == messages[1] == messages[2]
    assert "random_walk" in messages[0]
    cli = subprocess.run([str(host_bin), "-q", "export", "--calibration", str(hand["toml"]),
                          "--format", "kalibr", "--noise", str(faces_noise["json"])],
                         capture_output=True, text=True)
    assert cli.returncode != 0 and "random_walk" in cli.stderr


def test_export_refuses_a_noise_of_another_type(py_cal, faces_noise):
    doc, rows = faces_noise["doc"], faces_noise["rows"]
    for wrong in [42, 1.5, [1.0, 2.0], b"\x00"]:
        with pytest.raises(TypeError, match=r"noise must be a path to host noise's noise\.json, "
                                            r"or accelcal\.allan\(\)'s result .* got "):
            py_cal.export("kalibr", noise=wrong)
    with pytest.raises(TypeError, match=r"noise is a dict without 'rate_hz'"):
        py_cal.export("kalibr", noise={"white_density": 1.0})
    # One signal's curve, or the accelerometer's alone, cannot give both sensors' figures.
    one = accelcal.allan(rows[:, 1], doc["sample_rate_hz"])
    with pytest.raises(ValueError, match="result of one signal: Kalibr's figures need the six"):
        py_cal.export("kalibr", noise=one)
    three = accelcal.allan(rows[:, 1:4], doc["sample_rate_hz"])
    with pytest.raises(ValueError, match="result of 3 signals: Kalibr's figures need the six"):
        py_cal.export("kalibr", noise=three)
