"""Type stubs of accelcal (the compiled module and its Python half)."""

from os import PathLike
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

_Path = Union[str, PathLike]
_Rows3 = npt.ArrayLike  # (n, 3) float

DEFAULT_COLUMNS: Tuple[str, str, str, str, str, str]

class Error(Exception):
    """Every error of accelcal: `host`'s message, its options named as this package's keywords;
    `__cause__` holds what caused it (an `OSError` for a file the system could not read)."""

class InputError(Error):
    """The input cannot be used as given."""

class CalibrationError(Error):
    """The data give no calibration (too few positions, a refused gyro fit, a failed check, an
    export the calibration cannot fill)."""

class FileError(Error):
    """A file could not be read or written."""

class LogOptions:
    """How to read a logger's file or arrays (`host segment`'s input options)."""

    def __init__(
        self,
        *,
        acc_unit: Optional[str] = None,
        gyro_unit: Optional[str] = None,
        columns: Optional[Sequence[str]] = None,
        time_column: Optional[str] = None,
        time_unit: Optional[str] = None,
        rate_hz: Optional[float] = None,
        acc_offset: Optional[Sequence[float]] = None,
        gyro_lsb_per_dps: Optional[float] = None,
        gyro_offset: Optional[Sequence[float]] = None,
        temp_column: Optional[str] = None,
        instance: Optional[int] = None,
        topic: Optional[str] = None,
        skip_lines: Optional[int] = None,
    ) -> None: ...
    acc_unit: Optional[str]
    gyro_unit: Optional[str]
    columns: Optional[List[str]]
    time_column: Optional[str]
    time_unit: Optional[str]
    rate_hz: Optional[float]
    acc_offset: Optional[List[float]]
    gyro_lsb_per_dps: Optional[float]
    gyro_offset: Optional[List[float]]
    temp_column: Optional[str]
    instance: Optional[int]
    topic: Optional[str]
    skip_lines: Optional[int]

class SessionOptions:
    """How to cut a recording into a session: shortest still position, unit id, site, gyro fit."""

    def __init__(
        self,
        *,
        min_still_s: float = 1.0,
        unit_id: Optional[str] = None,
        gravity: Optional[float] = None,
        latitude: Optional[float] = None,
        height_m: Optional[float] = None,
        no_gyro: bool = False,
        face_sigma_deg: float = 2.0,
        faces: Optional[Sequence[str]] = None,
        max_samples: Optional[int] = None,
        still_threshold: Optional[Tuple[float, float]] = None,
    ) -> None: ...
    min_still_s: float
    unit_id: Optional[str]
    gravity: Optional[float]
    latitude: Optional[float]
    height_m: Optional[float]
    no_gyro: bool
    face_sigma_deg: float
    faces: Optional[List[str]]
    max_samples: Optional[int]
    still_threshold: Optional[Tuple[float, float]]

class Session:
    """A calibration session: plan, per-segment statistics and the hand-turn gyro."""

    @property
    def rate_hz(self) -> float: ...
    @property
    def acc_unit(self) -> str: ...
    @property
    def segments(self) -> List[str]: ...
    @property
    def warnings(self) -> List[str]: ...
    @property
    def advice(self) -> Optional[str]: ...
    def plan_toml(self) -> str: ...
    def intervals(self) -> List[Dict[str, Any]]: ...
    def gyro(self) -> Optional[Dict[str, Any]]: ...
    def write(self, dir: _Path, force: bool = False) -> int: ...

class Calibration:
    """A calibration estimated by `calibrate` or read by `Calibration.load`."""

    @staticmethod
    def load(path: _Path) -> Calibration: ...
    def to_toml(self) -> str: ...
    def to_blob(self, created_unix_s: Optional[int] = None) -> bytes: ...
    def save(self, dir: _Path, force: bool = False) -> Tuple[str, str]: ...
    def export(
        self,
        format: str,
        *,
        noise: Union[_Path, Dict[str, Any], None] = None,
        rostopic: str = "/imu0",
        driver_scale: Optional[float] = None,
        device_id: Optional[int] = None,
        gyro_device_id: Optional[int] = None,
        sysid: int = 1,
        compid: int = 1,
        allow_out_of_range: bool = False,
        allow_undetermined: bool = False,
    ) -> Union[str, Dict[str, str]]: ...
    @property
    def summary(self) -> Optional[Dict[str, Any]]: ...
    @property
    def file(self) -> Dict[str, Any]: ...
    @property
    def names(self) -> List[str]: ...
    @property
    def values(self) -> npt.NDArray[np.float64]: ...
    @property
    def sigmas(self) -> npt.NDArray[np.float64]: ...
    @property
    def units(self) -> List[str]: ...
    @property
    def gyro_matrix(self) -> Optional[npt.NDArray[np.float64]]: ...
    @property
    def gyro_matrix_1sigma(self) -> Optional[npt.NDArray[np.float64]]: ...
    @property
    def gyro_bias_rad_s(self) -> Optional[npt.NDArray[np.float64]]: ...
    @property
    def gyro_bias_rad_s_1sigma(self) -> Optional[npt.NDArray[np.float64]]: ...
    @property
    def temperature(self) -> Optional[Dict[str, Any]]: ...
    @property
    def warnings(self) -> List[str]: ...
    @property
    def undetermined(self) -> List[str]: ...
    @property
    def chi2(self) -> Optional[float]: ...
    @property
    def dof(self) -> Optional[int]: ...
    @property
    def chi2_per_dof(self) -> Optional[float]: ...
    @property
    def thermal_chi2_per_dof(self) -> Optional[Tuple[float, float, float]]: ...
    @property
    def passed(self) -> Optional[bool]: ...
    @property
    def unit_id(self) -> str: ...
    @property
    def created_unix_s(self) -> Optional[int]: ...

def segment(
    acc: Any,
    gyro: Optional[_Rows3] = None,
    t: Optional[npt.ArrayLike] = None,
    rate_hz: Optional[float] = None,
    *,
    columns: Sequence[str] = ...,
    time_column: Optional[str] = "t",
    log: Optional[LogOptions] = None,
    site: Optional[SessionOptions] = None,
    acc_unit: Optional[str] = None,
    gyro_unit: Optional[str] = None,
    time_unit: Optional[str] = None,
    acc_offset: Union[None, float, Sequence[float]] = None,
    gyro_lsb_per_dps: Optional[float] = None,
    gyro_offset: Union[None, float, Sequence[float]] = None,
    min_still_s: float = 1.0,
    unit_id: Optional[str] = None,
    gravity: Optional[float] = None,
    latitude: Optional[float] = None,
    height_m: Optional[float] = None,
    no_gyro: bool = False,
    face_sigma_deg: float = 2.0,
    faces: Optional[Sequence[str]] = None,
    still_threshold: Optional[Tuple[float, float]] = None,
) -> Session:
    """Cuts a recording (two (n, 3) array-likes, or one DataFrame with named columns) into a
    session; the reading options as `log=` or keywords, the cutting options as `site=` or
    keywords, not both for one group."""
    ...
def segment_file(
    path: _Path,
    *,
    log: Optional[LogOptions] = None,
    site: Optional[SessionOptions] = None,
    acc_unit: Optional[str] = None,
    gyro_unit: Optional[str] = None,
    columns: Optional[Sequence[str]] = None,
    time_column: Optional[str] = None,
    time_unit: Optional[str] = None,
    rate_hz: Optional[float] = None,
    acc_offset: Union[None, float, Sequence[float]] = None,
    gyro_lsb_per_dps: Optional[float] = None,
    gyro_offset: Union[None, float, Sequence[float]] = None,
    temp_column: Optional[str] = None,
    instance: Optional[int] = None,
    topic: Optional[str] = None,
    skip_lines: Optional[int] = None,
    min_still_s: float = 1.0,
    unit_id: Optional[str] = None,
    gravity: Optional[float] = None,
    latitude: Optional[float] = None,
    height_m: Optional[float] = None,
    no_gyro: bool = False,
    face_sigma_deg: float = 2.0,
    faces: Optional[Sequence[str]] = None,
    max_samples: Optional[int] = None,
    still_threshold: Optional[Tuple[float, float]] = None,
) -> Session:
    """Cuts a logger's file into a session, as ``host segment`` does: text (the units and time
    needed), PX4 ULog, ArduPilot DataFlash or ROS 2 MCAP (told by the first bytes; ``instance`` and
    ``topic`` choose the IMU); raw counts with ``acc_offset`` and ``gyro_lsb_per_dps``. The
    reading options as ``log=LogOptions(...)`` or keywords, the cutting options as
    ``site=SessionOptions(...)`` or keywords."""
    ...
def load_session(dir: _Path) -> Session: ...
def calibrate(
    session: Session,
    *,
    method: str = "joint",
    reference: str = "table-axis",
    single_package: bool = False,
    limits: Optional[Dict[str, float]] = None,
) -> Calibration: ...
def apply(
    calibration: Calibration,
    acc: Any,
    gyro: Optional[_Rows3] = None,
    t: Optional[npt.ArrayLike] = None,
    rate_hz: Optional[float] = None,
    *,
    temp_c: Union[None, float, npt.ArrayLike] = None,
    lever: str = "full",
    gyro_unit: str = "rad/s",
    with_rate: bool = False,
    columns: Sequence[str] = ...,
    time_column: Optional[str] = "t",
) -> Any:
    """The compensated specific force per row, g; a gyro whose rest does not fit ``gyro_unit``
    (°/s declared rad/s) raises InputError."""
    ...
def allan(x: npt.ArrayLike, rate_hz: float) -> Dict[str, Any]:
    """The Allan deviation and noise terms; a NaN or infinite value raises InputError."""
    ...
def simulate_hand(
    seed: int = 1,
    rate_hz: float = 200.0,
    acc_unit: str = "m/s2",
    gyro_unit: str = "deg/s",
    *,
    acc_offset: Optional[float] = None,
    gyro_lsb_per_dps: Optional[float] = None,
    as_frame: bool = False,
) -> Any: ...
def simulate(
    out: _Path,
    *,
    plan: Optional[str] = None,
    unit: Optional[_Path] = None,
    seed: int = 1,
    force: bool = False,
    no_noise: bool = False,
    noise_mg: Optional[float] = None,
    lsb: Optional[float] = None,
    drift_mg_sqrt_s: Optional[float] = None,
    tilt_deg: Optional[float] = None,
    rate_scale: Optional[float] = None,
    rate_offset_deg_s: Optional[float] = None,
    gyro_noise_deg_s: Optional[float] = None,
    gyro_bias_deg_s: Optional[Tuple[float, float, float]] = None,
    gyro_scale_ppm: Optional[Tuple[float, float, float]] = None,
    gyro_misalignment_deg: Optional[float] = None,
    flicker_mg: Optional[float] = None,
    gyro_drift_deg_s_sqrt_s: Optional[float] = None,
    gyro_flicker_deg_s: Optional[float] = None,
) -> Session: ...
