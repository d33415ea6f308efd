"""The package as a Python user meets it: typed keywords and option objects (no command-line
strings), exceptions of the promised types that keep their causes and name this package's keyword
arguments, one array-like rule for every function, and refusals where the numbers would be silently
wrong (a gyro in the wrong unit, a NaN in an Allan deviation)."""

import re
import tomllib
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import accelcal
from conftest import ROOT, UNIT_ID, run

ACC = ["acc_x", "acc_y", "acc_z"]
GYR = ["gyr_x", "gyr_y", "gyr_z"]


def test_the_compiled_half_uses_the_application_layer_not_the_command_line():
    sources = sorted((ROOT / "python" / "src").glob("*.rs"))
    assert sources
    for src in sources:
        text = src.read_text()
        assert "host::cli" not in text, src.name
        assert "CliError" not in text, src.name


def test_simulate_takes_typed_keywords(host_bin, tmp_path):
    # The command line's flags and Python's typed keywords write the same session.
    run(host_bin, "-q", "simulate", "--out", str(tmp_path / "cli"), "--plan", "short",
        "--seed", "4", "--gyro-bias-deg-s", "0.5,-0.25,0", "--noise-mg", "0.5")
    session = accelcal.simulate(tmp_path / "py", plan="short", seed=4,
                                gyro_bias_deg_s=(0.5, -0.25, 0.0), noise_mg=0.5)
    assert session.segments == accelcal.load_session(tmp_path / "cli").segments
    for name in ["plan.toml", "samples.csv", "truth.toml"]:
        assert (tmp_path / "py" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes(), name
    # Command-line strings are no keywords; a bias is three numbers.
    with pytest.raises(TypeError):
        accelcal.simulate(tmp_path / "x", args=["--plan", "short"])
    with pytest.raises((TypeError, ValueError)):
        accelcal.simulate(tmp_path / "x", gyro_bias_deg_s=(0.5, 0.0))


def test_segment_file_takes_grouped_options_or_the_same_keywords(hand):
    grouped = accelcal.segment_file(
        hand["csv"],
        log=accelcal.LogOptions(acc_unit="m/s2", gyro_unit="deg/s", time_column="t"),
        site=accelcal.SessionOptions(unit_id=UNIT_ID, min_still_s=1.0),
    )
    flat = accelcal.segment_file(hand["csv"], acc_unit="m/s2", gyro_unit="deg/s",
                                 time_column="t", unit_id=UNIT_ID)
    assert grouped.plan_toml() == flat.plan_toml() == (hand["session"] / "plan.toml").read_text()
    options = accelcal.LogOptions(acc_unit="g")
    assert options.acc_unit == "g" and options.gyro_unit is None
    with pytest.raises(accelcal.InputError, match="not both"):
        accelcal.segment_file(hand["csv"], log=options, acc_unit="m/s2")
    with pytest.raises(TypeError, match="acc_units"):
        accelcal.segment_file(hand["csv"], acc_units="m/s2")


def still_arrays(n=4000, seed=1):
    rng = np.random.default_rng(seed)
    acc = np.tile([0.0, 0.0, 9.80665], (n, 1)) + rng.normal(0, 0.01, (n, 3))
    gyro = rng.normal(0, 0.05, (n, 3))
    return acc, gyro, np.arange(n) / 200.0


def test_too_few_positions_is_a_calibration_error():
    acc, gyro, t = still_arrays()
    with pytest.raises(accelcal.CalibrationError, match="position"):
        accelcal.segment(acc, gyro, t, acc_unit="m/s2", gyro_unit="deg/s")


def test_an_exception_keeps_its_cause(tmp_path):
    with pytest.raises(accelcal.FileError) as e:
        accelcal.Calibration.load(tmp_path / "no-such.toml")
    assert isinstance(e.value.__cause__, FileNotFoundError), repr(e.value.__cause__)
    with pytest.raises(accelcal.FileError) as e:
        accelcal.load_session(tmp_path / "no-such-session")
    causes = []
    c = e.value.__cause__
    while c is not None:
        causes.append(c)
        c = c.__cause__
    assert any(isinstance(c, FileNotFoundError) for c in causes), causes


def test_errors_name_the_keyword_arguments(hand, py_cal_of_hand):
    messages = []
    with pytest.raises(accelcal.InputError) as e:
        accelcal.segment_file(hand["csv"], acc_unit="g", gyro_unit="deg/s", time_column="t")
    messages.append(str(e.value))
    assert 'acc_unit="m/s2"' in messages[-1]
    with pytest.raises(accelcal.InputError) as e:
        accelcal.segment_file(hand["csv"], acc_unit="m/s2", gyro_unit="LSB", time_column="t")
    messages.append(str(e.value))
    assert "gyro_lsb_per_dps=X" in messages[-1]
    with pytest.raises(accelcal.InputError) as e:
        accelcal.segment_file(hand["csv"], acc_unit="m/s2", gyro_unit="deg/s")
    messages.append(str(e.value))
    assert 'time_column="NAME" or rate_hz=HZ' in messages[-1]
    with pytest.raises(accelcal.CalibrationError) as e:
        py_cal_of_hand.export("px4")
    messages.append(str(e.value))
    assert "give device_id=ID" in messages[-1]
    with pytest.raises(accelcal.CalibrationError) as e:
        py_cal_of_hand.export("ardupilot", device_id=1 << 25)
    messages.append(str(e.value))
    assert messages[-1].startswith("device_id=33554432: ArduPilot sends INS_ACC_ID as a float")
    # The single-package model refused for the paper's method.
    session = accelcal.load_session(hand["session"])
    with pytest.raises(accelcal.CalibrationError) as e:
        accelcal.calibrate(session, method="paper", single_package=True)
    messages.append(str(e.value))
    assert 'use method="joint" with single_package=True' in messages[-1]
    # The IMU of a binary log: a missing instance, a topic the bag does not have.
    logs = ROOT / "recording" / "tests" / "fixtures" / "logs"
    with pytest.raises(accelcal.InputError) as e:
        accelcal.segment_file(logs / "hand.ulg", instance=1)
    messages.append(str(e.value))
    assert "choose the IMU with instance=N" in messages[-1]
    with pytest.raises(accelcal.InputError) as e:
        accelcal.segment_file(logs / "hand.mcap", topic="/nope")
    messages.append(str(e.value))
    assert 'topic="/nope": not a' in messages[-1]
    # A gyro in rad/s declared deg/s: its turns are 1/57 of gravity's, an input in the wrong unit.
    d = accelcal.simulate_hand(seed=3)
    with pytest.raises(accelcal.InputError) as e:
        accelcal.segment(d["acc"], np.radians(d["gyro"]), d["t"], acc_unit="m/s2",
                         gyro_unit="deg/s")
    messages.append(str(e.value))
    assert 'gyro_unit="rad/s"' in messages[-1]
    for m in messages:
        assert not re.search(r"(^|\W)--[a-z]", m), m


def test_save_refuses_to_replace_and_names_force(hand, tmp_path):
    cal = accelcal.calibrate(accelcal.load_session(hand["session"]))
    cal.save(tmp_path)
    with pytest.raises(accelcal.FileError, match=r"force=True") as e:
        cal.save(tmp_path)
    assert "--" not in str(e.value)
    cal.save(tmp_path, force=True)
    session = accelcal.segment_file(hand["csv"], acc_unit="m/s2", gyro_unit="deg/s",
                                    time_column="t")
    session.write(tmp_path / "s")
    with pytest.raises(accelcal.FileError, match=r"force=True") as e:
        session.write(tmp_path / "s")
    assert "--" not in str(e.value)


def test_an_export_out_of_range_names_the_keyword(py_cal_of_hand):
    # A driver scale 100 times too small puts ArduPilot's scales far outside 0.8..1.2.
    with pytest.raises(accelcal.CalibrationError) as e:
        py_cal_of_hand.export("ardupilot", device_id=1, driver_scale=0.01)
    m = str(e.value)
    assert "allow_out_of_range=True" in m and "driver_scale" in m, m
    assert not re.search(r"(^|\W)--[a-z]", m), m


@pytest.fixture(scope="module")
def py_cal_of_hand(hand):
    return accelcal.Calibration.load(hand["toml"])


def test_apply_refuses_a_gyro_in_deg_s_declared_rad_s(hand):
    cal = accelcal.Calibration.load(hand["toml"])
    d = accelcal.simulate_hand(seed=3)  # the gyro in deg/s, as the hand session's logger wrote it
    with pytest.raises(accelcal.InputError, match='gyro_unit="deg/s"'):
        accelcal.apply(cal, d["acc"], d["gyro"], d["t"])  # gyro_unit defaults to rad/s
    f = accelcal.apply(cal, d["acc"], d["gyro"], d["t"], gyro_unit="deg/s")
    assert f.shape == d["acc"].shape
    # Against the simulator: a still hand is at 1 g (the truth is the simulated gravity).
    assert abs(np.median(np.linalg.norm(f, axis=1)) - 1.0) < 5e-3


def test_allan_refuses_a_nan():
    x = np.random.default_rng(2).normal(0, 1e-3, 20000)
    clean = accelcal.allan(x, rate_hz=100.0)
    assert np.all(np.isfinite(clean["adev"]))
    x[1234] = np.nan
    with pytest.raises(accelcal.InputError, match="index 1234"):
        accelcal.allan(x, rate_hz=100.0)
    with pytest.raises(accelcal.InputError, match="non-finite"):
        accelcal.allan(np.column_stack([x, x]), rate_hz=100.0)


def test_every_function_takes_the_same_array_likes(hand):
    d = accelcal.simulate_hand(seed=3, as_frame=True)
    arrays = accelcal.segment(d[ACC].to_numpy(), d[GYR].to_numpy(), d["t"].to_numpy(),
                              acc_unit="m/s2", gyro_unit="deg/s", unit_id=UNIT_ID)
    frame_pair = accelcal.segment(d[ACC], d[GYR], d["t"], acc_unit="m/s2", gyro_unit="deg/s",
                                  unit_id=UNIT_ID)
    one_frame = accelcal.segment(d, acc_unit="m/s2", gyro_unit="deg/s", unit_id=UNIT_ID)
    assert arrays.plan_toml() == frame_pair.plan_toml() == one_frame.plan_toml()
    cal = accelcal.calibrate(arrays)
    f_arrays = accelcal.apply(cal, d[ACC].to_numpy(), np.radians(d[GYR].to_numpy()),
                              d["t"].to_numpy())
    f_pair = accelcal.apply(cal, d[ACC], np.radians(d[GYR]), d["t"])
    f_frame = accelcal.apply(cal, d, gyro_unit="deg/s")
    np.testing.assert_array_equal(f_arrays, f_pair)
    # deg/s converted here or by numpy: the same rates to an ulp, the same f32 force to 1e-6 g.
    np.testing.assert_allclose(f_frame, f_arrays, rtol=0, atol=1e-6)
    a = accelcal.allan(d["gyr_x"], rate_hz=200.0)
    b = accelcal.allan(d["gyr_x"].to_numpy(), rate_hz=200.0)
    np.testing.assert_array_equal(a["adev"], b["adev"])


def test_the_readme_installs_what_the_readme_uses():
    readme = (ROOT / "python" / "README.md").read_text()
    project = tomllib.loads((ROOT / "python" / "pyproject.toml").read_text())["project"]
    extra = project["optional-dependencies"]["pandas"]
    assert any(re.match(r"pandas\b", r) for r in extra), extra
    installs = re.findall(r"pip install (.+)", readme)
    assert installs, "no pip install line"
    assert any("[pandas]" in line for line in installs), installs
    # The example uses pandas (a DataFrame): the extra is what brings it.
    code = "".join(re.findall(r"```python\n(.*?)```", readme, flags=re.S))
    assert "as_frame=True" in code or "import pandas" in code


def test_faces_labelled_by_the_user_are_checked_against_the_data(host_bin, tmp_path):
    # A cube on its six faces; the labels as the automatic labelling reads each still position.
    run(host_bin, "-q", "simulate-hand", "--six-faces", "--out", str(tmp_path / "cube.csv"))
    reading = dict(acc_unit="m/s2", gyro_unit="deg/s", time_column="t")
    auto = accelcal.segment_file(tmp_path / "cube.csv", **reading)
    ups = re.findall(r"up_b = \[([^\]]*)\]", auto.plan_toml())
    labels = []
    for up in ups:
        v = [float(x) for x in up.split(",") if x.strip()]
        j = max(range(3), key=lambda i: abs(v[i]))
        labels.append("xyz"[j] + ("+" if v[j] > 0 else "-"))
    assert len(labels) == 6, auto.plan_toml()
    given = accelcal.segment_file(tmp_path / "cube.csv", faces=labels, **reading)
    assert given.plan_toml() == auto.plan_toml()
    swapped = [labels[1], labels[0]] + labels[2:]
    with pytest.raises(accelcal.InputError, match="still interval 1 is labelled"):
        accelcal.segment_file(tmp_path / "cube.csv", faces=swapped, **reading)
    with pytest.raises(accelcal.InputError, match="'up' is not a face"):
        accelcal.segment_file(tmp_path / "cube.csv", faces=["up"] * 6, **reading)


def _stub():
    """The package's type stub, parsed: its classes' members and its functions' keywords."""
    import ast

    tree = ast.parse((ROOT / "python" / "accelcal" / "__init__.pyi").read_text())
    classes, functions = {}, {}
    for node in tree.body:
        if isinstance(node, ast.ClassDef):
            members = {}
            for item in node.body:
                if isinstance(item, ast.FunctionDef):
                    members[item.name] = {a.arg for a in item.args.kwonlyargs + item.args.args}
                elif isinstance(item, ast.AnnAssign):
                    members[item.target.id] = set()
            classes[node.name] = members
        elif isinstance(node, ast.FunctionDef):
            functions[node.name] = {a.arg for a in node.args.kwonlyargs + node.args.args}
    return classes, functions


def test_the_type_stub_has_every_option_and_property_the_package_has():
    # An editor's completion and a type checker read the stub, not the package: an option or a
    # property missing from it is one they refuse.
    classes, functions = _stub()
    log_keywords, site_keywords = set(accelcal._LOG_KEYWORDS), set(accelcal._SESSION_KEYWORDS)
    assert classes["LogOptions"]["__init__"] - {"self"} == log_keywords
    assert classes["SessionOptions"]["__init__"] - {"self"} == site_keywords
    for name in ["LogOptions", "SessionOptions"]:
        keywords = log_keywords if name == "LogOptions" else site_keywords
        assert keywords <= set(classes[name]), (name, keywords - set(classes[name]))
    missing = (log_keywords | site_keywords) - functions["segment_file"]
    assert not missing, missing
    for cls in ["Calibration", "Session"]:
        runtime = {n for n in dir(getattr(accelcal, cls)) if not n.startswith("_")}
        assert runtime <= set(classes[cls]), (cls, sorted(runtime - set(classes[cls])))


def test_a_gyro_at_an_unsigned_mid_scale_is_named_for_arrays_as_for_a_file():
    # An unsigned 16-bit gyro reads its zero rate at 32768 counts: the fit would take it for a bias
    # of 500 °/s. The note names the keyword that removes it, as host segment names its option.
    d = accelcal.simulate_hand(seed=3)
    lsb = 65.5
    counts = np.round(np.asarray(d["gyro"]) * lsb) + 32768.0
    keywords = dict(acc_unit="m/s2", gyro_unit="LSB", gyro_lsb_per_dps=lsb, unit_id=UNIT_ID)
    raw = accelcal.segment(d["acc"], counts, d["t"], **keywords)
    notes = [w for w in raw.warnings if "mid-scale" in w]
    assert len(notes) == 1 and "gyro_offset=32768" in notes[0], raw.warnings
    centred = accelcal.segment(d["acc"], counts, d["t"], gyro_offset=32768, **keywords)
    assert not any("mid-scale" in w for w in centred.warnings), centred.warnings


def test_simulate_hand_refuses_as_python_spells_it_and_writes_counts():
    """The simulated hand session is the command line's use case: its refusals name Python's
    keywords, and counts come out as a logger writes them (whole gyro counts, the offset added)."""
    for kwargs, words in [
        (dict(gyro_unit="LSB"), 'gyro_unit="LSB" and gyro_lsb_per_dps=X go together'),
        (dict(acc_offset=32768.0), 'acc_offset needs acc_unit="LSB"'),
        (dict(rate_hz=5.0), "rate_hz=5: use 20 to 10000"),
    ]:
        with pytest.raises(accelcal.InputError) as e:
            accelcal.simulate_hand(seed=3, **kwargs)
        assert str(e.value) == words
    plain = accelcal.simulate_hand(seed=3, acc_unit="LSB")
    d = accelcal.simulate_hand(seed=3, acc_unit="LSB", acc_offset=32768.0, gyro_unit="LSB",
                               gyro_lsb_per_dps=16.4)
    assert np.array_equal(d["acc"], plain["acc"] + 32768.0)
    assert np.array_equal(d["gyro"], np.round(d["gyro"]))
    # The same rates: counts at 16.4 per °/s against the °/s of the default gyro unit.
    deg = accelcal.simulate_hand(seed=3, acc_unit="LSB")["gyro"]
    assert np.max(np.abs(d["gyro"] / 16.4 - deg)) <= 0.5 / 16.4 + 1e-9
