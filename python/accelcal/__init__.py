"""accel-cal from Python: calibrate a strap-down tri-axis accelerometer unit from numpy arrays or a
pandas DataFrame, with the same library (and so the same numbers and files) as the ``host`` command.

    session = accelcal.segment(df, acc_unit="m/s2", gyro_unit="deg/s")   # host segment
    cal = accelcal.calibrate(session)                                      # host calibrate --input
    cal.to_toml(), cal.to_blob(), cal.export("px4", device_id=1)           # calibration.toml/.bin, host export
    f_g = accelcal.apply(cal, acc, gyro, rate_hz=200.0)                    # host apply
    curve = accelcal.allan(gyro[:, 0], rate_hz=200.0)                      # host noise

Errors are raised as ``accelcal.Error`` (``InputError``, ``CalibrationError``, ``FileError``) with
the message the command line prints for the same failure.
"""

from __future__ import annotations

from typing import Any, Optional, Sequence

import numpy as np

from ._accelcal import (
    CalibrationError,
    Calibration,
    Error,
    FileError,
    InputError,
    Session,
    calibrate,
    load_session,
    segment_file,
)
from . import _accelcal

__all__ = [
    "Calibration",
    "CalibrationError",
    "Error",
    "FileError",
    "InputError",
    "Session",
    "allan",
    "apply",
    "calibrate",
    "load_session",
    "segment",
    "segment_file",
    "simulate",
    "simulate_hand",
]

#: The column names ``segment`` looks for in a DataFrame (``host segment``'s default ``--columns``).
DEFAULT_COLUMNS = ("acc_x", "acc_y", "acc_z", "gyr_x", "gyr_y", "gyr_z")


def _rows3(a: Any, what: str) -> np.ndarray:
    """An (n, 3) float64 array, the caller's own memory when it already is one."""
    arr = np.asarray(a, dtype=np.float64)
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise InputError(f"{what} must be an array of shape (n, 3); got shape {arr.shape}")
    return arr


def _is_frame(x: Any) -> bool:
    return hasattr(x, "columns") and hasattr(x, "to_numpy")


def segment(
    acc: Any,
    gyro: Any = None,
    t: Any = None,
    rate_hz: Optional[float] = None,
    *,
    acc_unit: str,
    gyro_unit: str,
    columns: Sequence[str] = DEFAULT_COLUMNS,
    time_column: Optional[str] = "t",
    **options: Any,
) -> Session:
    """Cut a continuous hand-held recording into a calibration session (``host segment``).

    ``acc`` and ``gyro`` are (n, 3) arrays, or ``acc`` is a pandas DataFrame whose columns are named
    (``columns``: acc x, y, z then gyro x, y, z; ``time_column`` in seconds when present, else give
    ``rate_hz``). ``acc_unit`` is "m/s2", "g", "LSB" or "V" (it becomes the calibration's output
    unit), ``gyro_unit`` "deg/s", "rad/s" or "LSB". Options as ``host segment``'s flags, checked by
    its own option set: ``time_unit`` ("s", "ms", "us", "ns"; else detected), ``acc_offset`` (raw
    counts' zero force, one value or one per axis), ``gyro_lsb_per_dps`` (with ``gyro_unit="LSB"``),
    ``min_still_s``, ``unit_id``, ``gravity``, ``latitude``, ``height_m``, ``no_gyro``,
    ``face_sigma_deg``.

    C-contiguous float64 arrays are read in place (no copy); other layouts are converted once.
    """
    if _is_frame(acc):
        frame = acc
        if gyro is not None:
            raise InputError("give a DataFrame alone, or acc and gyro arrays")
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
    elif gyro is None:
        raise InputError("give acc and gyro as (n, 3) arrays, or a DataFrame with named columns")
    acc = np.ascontiguousarray(_rows3(acc, "acc"))
    gyro = np.ascontiguousarray(_rows3(gyro, "gyro"))
    if t is not None:
        t = np.ascontiguousarray(np.asarray(t, dtype=np.float64))
    return _accelcal.segment_arrays(
        acc, gyro, t, rate_hz, acc_unit=acc_unit, gyro_unit=gyro_unit, **options
    )


def apply(
    calibration: Calibration,
    acc: Any,
    gyro: Any,
    t: Any = None,
    rate_hz: Optional[float] = None,
    *,
    temp_c: Any = None,
    lever: str = "full",
    gyro_unit: str = "rad/s",
    with_rate: bool = False,
) -> Any:
    """The compensated specific force, g, body axes, of each row (``host apply``): the device's
    own f32 path (``shared::Compensator`` and the firmware's ω̇ estimator). With ``with_rate``,
    a pair: the force and the corrected body rate of each row, rad/s (``host apply``'s ``w_*``).

    The sample rate is ``rate_hz``, or from ``t`` (seconds; the median step, as ``segment`` reads
    a logger's time column). ``temp_c``: one temperature, or one per row (needed when the
    calibration has a temperature model). ``lever``: "off", "rate" or "full" (the device's modes).
    """
    acc = _rows3(acc, "acc")
    gyro = _rows3(gyro, "gyro")
    if rate_hz is None:
        if t is None:
            raise InputError("give the sample rate: rate_hz=HZ, or t (seconds)")
        steps = np.sort(np.diff(np.asarray(t, dtype=np.float64)))
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
    ``upper_bound_2sigma``, ``needs_recording_s``. For (n, k) input every entry is a list of k.
    """
    arr = np.asarray(x, dtype=np.float64)
    if arr.ndim == 1:
        return _accelcal.allan(arr, float(rate_hz))
    if arr.ndim != 2:
        raise InputError(f"x must be (n,) or (n, k); got shape {arr.shape}")
    columns = [_accelcal.allan(np.ascontiguousarray(arr[:, j]), float(rate_hz)) for j in range(arr.shape[1])]
    return {key: [c[key] for c in columns] for key in columns[0]}


def simulate_hand(
    seed: int = 1,
    rate_hz: float = 200.0,
    acc_unit: str = "m/s2",
    gyro_unit: str = "deg/s",
    *,
    as_frame: bool = False,
) -> Any:
    """A simulated hand-held session (``host simulate-hand``): a dict with ``t``, ``acc``, ``gyro``
    and ``truth_toml``, or with ``as_frame=True`` a pandas DataFrame with the logger's columns
    (t, acc_x … gyr_z) and the truth in ``df.attrs["truth_toml"]``."""
    d = _accelcal.simulate_hand(seed, float(rate_hz), acc_unit, gyro_unit)
    if not as_frame:
        return d
    import pandas as pd

    data = {"t": d["t"]}
    for k, name in enumerate(DEFAULT_COLUMNS):
        data[name] = (d["acc"] if k < 3 else d["gyro"])[:, k % 3]
    frame = pd.DataFrame(data)
    frame.attrs["truth_toml"] = d["truth_toml"]
    return frame


def simulate(out: Any, **flags: Any) -> Session:
    """A session on the virtual rate table (``host simulate --out OUT``), read back. Keyword flags
    are ``host simulate``'s: ``plan="oblique"``, ``seed=3``, ``unit="unit.toml"``,
    ``no_noise=True``, ``force=True``…"""
    args: list = []
    for key, value in flags.items():
        flag = "--" + key.replace("_", "-")
        if value is True:
            args.append(flag)
        elif value is not False and value is not None:
            args += [flag, str(value)]
    return _accelcal.simulate(str(out), args)
