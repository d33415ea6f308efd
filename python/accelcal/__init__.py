"""accel-cal from Python: calibrate a strap-down tri-axis accelerometer unit from numpy arrays or a
pandas DataFrame, with the same library (and so the same numbers and files) as the ``host`` command.

    session = accelcal.segment(df, acc_unit="m/s2", gyro_unit="deg/s")   # host segment
    cal = accelcal.calibrate(session)                                      # host calibrate --input
    cal.to_toml(), cal.to_blob(), cal.export("px4", device_id=1)           # calibration.toml/.bin, host export
    f_g = accelcal.apply(cal, acc, gyro, rate_hz=200.0)                    # host apply
    curve = accelcal.allan(gyro[:, 0], rate_hz=200.0)                      # host noise

Errors are raised as ``accelcal.Error`` (``InputError``, ``CalibrationError``, ``FileError``); their
messages name this package's keyword arguments, and ``__cause__`` holds what caused them (an
``OSError`` for a file the system could not read).
"""

from __future__ import annotations

from typing import Any, Dict, Optional, Sequence, Tuple

import numpy as np

from ._accelcal import (
    CalibrationError,
    Calibration,
    Error,
    FileError,
    InputError,
    LogOptions,
    Session,
    SessionOptions,
    calibrate,
    load_session,
)
from . import _accelcal

__all__ = [
    "Calibration",
    "CalibrationError",
    "Error",
    "FileError",
    "InputError",
    "LogOptions",
    "Session",
    "SessionOptions",
    "allan",
    "apply",
    "calibrate",
    "load_session",
    "segment",
    "segment_file",
    "simulate",
    "simulate_hand",
]

#: The column names ``segment`` and ``apply`` look for in a DataFrame (``host segment``'s default
#: ``--columns``).
DEFAULT_COLUMNS = ("acc_x", "acc_y", "acc_z", "gyr_x", "gyr_y", "gyr_z")

#: The keywords of ``LogOptions`` (how to read a log) and of ``SessionOptions`` (how to cut it).
_LOG_KEYWORDS = (
    "acc_unit", "gyro_unit", "columns", "time_column", "time_unit", "rate_hz", "acc_offset",
    "gyro_lsb_per_dps", "gyro_offset", "temp_column", "instance", "topic", "skip_lines",
)
_SESSION_KEYWORDS = (
    "min_still_s", "unit_id", "gravity", "latitude", "height_m", "no_gyro", "face_sigma_deg",
    "faces", "max_samples", "still_threshold",
)


def _rows3(a: Any, what: str) -> np.ndarray:
    """An (n, 3) float64 array, the caller's own memory when it already is one."""
    arr = np.asarray(a, dtype=np.float64)
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise InputError(f"{what} must be an array of shape (n, 3); got shape {arr.shape}")
    return arr


def _is_frame(x: Any) -> bool:
    return hasattr(x, "columns") and hasattr(x, "to_numpy")


def _rows(
    acc: Any, gyro: Any, t: Any, rate_hz: Optional[float], columns: Sequence[str],
    time_column: Optional[str],
) -> Tuple[np.ndarray, np.ndarray, Optional[np.ndarray]]:
    """The one array-like rule of every function: ``acc`` and ``gyro`` as two (n, 3) array-likes
    (numpy arrays, DataFrames, nested lists), or ``acc`` alone as a DataFrame with named columns
    (``columns``; the time from ``time_column`` when present and neither ``t`` nor ``rate_hz`` is
    given). Returns float64 arrays (acc, gyro, t or None)."""
    if gyro is None:
        if not _is_frame(acc):
            raise InputError(
                "give acc and gyro as (n, 3) arrays or DataFrames, or one DataFrame with named "
                "columns"
            )
        frame = acc
        names = {str(c).lower(): c for c in frame.columns}
        missing = [c for c in columns if c.lower() not in names]
        if len(columns) != 6 or missing:
            raise InputError(
                f"column '{missing[0] if missing else columns}' is not in the DataFrame "
                f"({', '.join(map(str, frame.columns))}); name its columns with "
                "columns=(ACC_X, ACC_Y, ACC_Z, GYR_X, GYR_Y, GYR_Z) (and time_column=NAME)"
            )
        pick = [names[c.lower()] for c in columns]
        acc = frame[pick[:3]].to_numpy(dtype=np.float64)
        gyro = frame[pick[3:]].to_numpy(dtype=np.float64)
        if t is None and rate_hz is None and time_column is not None:
            if time_column.lower() not in names:
                raise InputError(
                    f"the DataFrame has no time column '{time_column}': name it with "
                    "time_column=NAME, or give rate_hz=HZ"
                )
            t = frame[names[time_column.lower()]].to_numpy(dtype=np.float64)
    acc = _rows3(acc, "acc")
    gyro = _rows3(gyro, "gyro")
    if t is not None:
        t = np.asarray(t, dtype=np.float64)
        if t.ndim != 1:
            raise InputError(f"t must be one time per row, shape (n,); got shape {t.shape}")
    return acc, gyro, t


def _options(
    log: Optional[LogOptions], site: Optional[SessionOptions], keywords: Dict[str, Any],
) -> Tuple[LogOptions, SessionOptions]:
    """The two option groups: given whole (``log=LogOptions(...)``, ``site=SessionOptions(...)``),
    or built from the same names as flat keywords; not both for one group."""
    unknown = sorted(set(keywords) - set(_LOG_KEYWORDS) - set(_SESSION_KEYWORDS))
    if unknown:
        raise TypeError(f"unexpected keyword argument(s): {', '.join(unknown)}")
    log_kw = {k: keywords[k] for k in _LOG_KEYWORDS if keywords.get(k) is not None}
    site_kw = {k: keywords[k] for k in _SESSION_KEYWORDS if k in keywords}
    # The raw counts' offsets: one value for every axis, or one per axis.
    for name in ("acc_offset", "gyro_offset"):
        offset = log_kw.get(name)
        if offset is not None and np.ndim(offset) == 0:
            log_kw[name] = [offset]
        elif offset is not None:
            log_kw[name] = [float(v) for v in offset]
    if "columns" in log_kw:
        log_kw["columns"] = list(log_kw["columns"])
    if log is not None and log_kw:
        raise InputError(
            f"give log=LogOptions(...) or its keywords ({', '.join(log_kw)}), not both"
        )
    if site is not None and site_kw:
        raise InputError(
            f"give site=SessionOptions(...) or its keywords ({', '.join(site_kw)}), not both"
        )
    return log or LogOptions(**log_kw), site or SessionOptions(**site_kw)


def segment(
    acc: Any,
    gyro: Any = None,
    t: Any = None,
    rate_hz: Optional[float] = None,
    *,
    columns: Sequence[str] = DEFAULT_COLUMNS,
    time_column: Optional[str] = "t",
    log: Optional[LogOptions] = None,
    site: Optional[SessionOptions] = None,
    **keywords: Any,
) -> Session:
    """Cut a continuous hand-held recording into a calibration session (``host segment``).

    ``acc`` and ``gyro`` are (n, 3) array-likes (numpy arrays or DataFrames), or ``acc`` is one
    pandas DataFrame whose columns are named (``columns``: acc x, y, z then gyro x, y, z;
    ``time_column`` in seconds when present, else give ``t`` or ``rate_hz``).

    How to read the values, as ``log=LogOptions(...)`` or its keywords: ``acc_unit`` ("m/s2",
    "g", "LSB" or "V": the calibration's output unit) and ``gyro_unit`` ("deg/s", "rad/s" or
    "LSB"), both needed; ``time_unit`` ("s", "ms", "us", "ns"; else detected), ``acc_offset`` (raw
    counts' zero force, one value or one per axis), ``gyro_lsb_per_dps`` (with
    ``gyro_unit="LSB"``). How to cut it, as ``site=SessionOptions(...)`` or its keywords:
    ``min_still_s``, ``unit_id``, ``gravity``, ``latitude``, ``height_m``, ``no_gyro``,
    ``face_sigma_deg``, ``faces`` (one label per still position in order, "x+" … "z-": a six-face
    session checked against the data), ``still_threshold`` ((mg, °/s): fixed limits on a still
    window's spread instead of the sensor's own noise floor).

    C-contiguous float64 arrays are read in place (no copy); other layouts are converted once.
    """
    log, site = _options(log, site, keywords)
    acc, gyro, t = _rows(acc, gyro, t, rate_hz, columns, time_column)
    acc = np.ascontiguousarray(acc)
    gyro = np.ascontiguousarray(gyro)
    if t is not None:
        t = np.ascontiguousarray(t)
    return _accelcal.segment_arrays(acc, gyro, t, rate_hz, log, site)


def segment_file(
    path: Any,
    *,
    log: Optional[LogOptions] = None,
    site: Optional[SessionOptions] = None,
    **keywords: Any,
) -> Session:
    """Cut a logger's file into a session (``host segment --input``): text (its units and time
    needed), PX4 ULog, ArduPilot DataFlash or ROS 2 MCAP (told by the first bytes). How to read it
    as ``log=LogOptions(...)`` or its keywords (``acc_unit``, ``gyro_unit``, ``columns``,
    ``time_column``, ``time_unit``, ``rate_hz``, ``acc_offset``, ``gyro_lsb_per_dps``,
    ``gyro_offset``, ``temp_column``, ``instance``, ``topic``); how to cut it as ``site=SessionOptions(...)`` or its keywords, with
    ``max_samples``: the samples of each stream held in memory at once (default 250 000, about
    200 bytes each); a longer log is read again and only its still positions and turns are kept."""
    log, site = _options(log, site, keywords)
    return _accelcal.segment_file(str(path), log, site)


def apply(
    calibration: Calibration,
    acc: Any,
    gyro: Any = None,
    t: Any = None,
    rate_hz: Optional[float] = None,
    *,
    temp_c: Any = None,
    lever: str = "full",
    gyro_unit: str = "rad/s",
    with_rate: bool = False,
    columns: Sequence[str] = DEFAULT_COLUMNS,
    time_column: Optional[str] = "t",
) -> Any:
    """The compensated specific force, g, body axes, of each row (``host apply``): the device's
    own f32 path (``shared::Compensator`` and the firmware's ω̇ estimator). With ``with_rate``,
    a pair: the force and the corrected body rate of each row, rad/s (``host apply``'s ``w_*``).

    ``acc`` and ``gyro`` as ``segment`` takes them (two (n, 3) array-likes, or one DataFrame with
    named columns). The sample rate is ``rate_hz``, or from ``t`` (seconds; the median step, as
    ``segment`` reads a logger's time column). ``gyro_unit``: "rad/s" or "deg/s"; as ``host
    apply`` checks a logger's file, the still intervals found in the rows must compensate to 1 g
    and rest, so a gyro in °/s given as rad/s is refused (``InputError``). ``temp_c``: one
    temperature, or one per row (needed when the calibration has a temperature model).
    ``lever``: "off", "rate" or "full" (the device's modes).
    """
    acc, gyro, t = _rows(acc, gyro, t, rate_hz, columns, time_column)
    if rate_hz is None:
        if t is None:
            raise InputError("give the sample rate: rate_hz=HZ, or t (seconds)")
        steps = np.sort(np.diff(t))
        if steps.size == 0 or not steps[steps.size // 2] > 0:
            raise InputError("t must increase: give the time of each row in seconds")
        rate_hz = float(1.0 / steps[steps.size // 2])
    if temp_c is not None and not np.isscalar(temp_c):
        temp_c = np.ascontiguousarray(np.asarray(temp_c, dtype=np.float64))
    return _accelcal.apply(
        calibration, acc, gyro, float(rate_hz), temp_c=temp_c, lever=lever, gyro_unit=gyro_unit,
        with_rate=with_rate,
    )


def allan(x: Any, rate_hz: float) -> dict:
    """The overlapping Allan deviation of a still signal at octave-spaced τ (``host noise``).

    ``x``: one signal (n,) or several as columns (n, k). Returns a dict with ``tau_s``, ``adev``,
    ``adev_low``/``adev_high`` (1σ bounds), ``terms`` (the sum's length), ``fit_adev`` and the
    fitted noise terms ``white_density`` (N, unit/√Hz), ``bias_instability`` (B, unit) and
    ``random_walk`` (K, unit/√s), each a dict: ``value`` (None when not determined), ``sigma``,
    ``upper_bound_2sigma``, ``needs_recording_s``, and ``rate_hz``. For (n, k) input every entry
    but ``rate_hz`` is a list of k. A NaN or infinite value is refused (``InputError``): it would
    make every τ's deviation NaN.

    The result of the six still signals ``host noise`` analyses, as columns (accel x, y, z in m/s²,
    gyro x, y, z in rad/s), is what ``Calibration.export("kalibr", noise=…)`` takes in place of
    ``noise.json``: the same figures.
    """
    arr = np.asarray(x, dtype=np.float64)
    if arr.ndim == 1:
        return _accelcal.allan(arr, float(rate_hz))
    if arr.ndim != 2:
        raise InputError(f"x must be (n,) or (n, k); got shape {arr.shape}")
    columns = [_accelcal.allan(np.ascontiguousarray(arr[:, j]), float(rate_hz)) for j in range(arr.shape[1])]
    result = {key: [c[key] for c in columns] for key in columns[0]}
    result["rate_hz"] = float(rate_hz)
    return result


def simulate_hand(
    seed: int = 1,
    rate_hz: float = 200.0,
    acc_unit: str = "m/s2",
    gyro_unit: str = "deg/s",
    *,
    acc_offset: Optional[float] = None,
    gyro_lsb_per_dps: Optional[float] = None,
    as_frame: bool = False,
) -> Any:
    """A simulated hand-held session (``host simulate-hand``): a dict with ``t``, ``acc``, ``gyro``
    and ``truth_toml``, or with ``as_frame=True`` a pandas DataFrame with the logger's columns
    (t, acc_x … gyr_z) and the truth in ``df.attrs["truth_toml"]``. ``acc_offset`` (with
    ``acc_unit="LSB"``) adds an unsigned output's mid-scale to every accelerometer value;
    ``gyro_unit="LSB"`` writes whole gyro counts at ``gyro_lsb_per_dps``."""
    d = _accelcal.simulate_hand(
        seed,
        float(rate_hz),
        acc_unit,
        gyro_unit,
        acc_offset=None if acc_offset is None else float(acc_offset),
        gyro_lsb_per_dps=None if gyro_lsb_per_dps is None else float(gyro_lsb_per_dps),
    )
    if not as_frame:
        return d
    import pandas as pd

    data = {"t": d["t"]}
    for k, name in enumerate(DEFAULT_COLUMNS):
        data[name] = (d["acc"] if k < 3 else d["gyro"])[:, k % 3]
    frame = pd.DataFrame(data)
    frame.attrs["truth_toml"] = d["truth_toml"]
    return frame


def simulate(out: Any, **options: Any) -> Session:
    """A session on the virtual rate table (``host simulate``), written to ``out`` and read back.
    Typed keywords: ``plan`` (a built-in plan's name or a plan file), ``seed``, ``unit`` (a unit
    file), ``force``, and the noise: ``no_noise``, ``noise_mg``, ``lsb``, ``drift_mg_sqrt_s``,
    ``tilt_deg``, ``rate_scale``, ``rate_offset_deg_s``, ``gyro_noise_deg_s``,
    ``gyro_bias_deg_s`` (x, y, z), ``gyro_scale_ppm`` (x, y, z), ``gyro_misalignment_deg``,
    ``flicker_mg``, ``gyro_drift_deg_s_sqrt_s``, ``gyro_flicker_deg_s``."""
    if "unit" in options and options["unit"] is not None:
        options["unit"] = str(options["unit"])
    return _accelcal.simulate(str(out), **options)
