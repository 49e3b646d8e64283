"""The calibration file: versioned JSON, SI units, written atomically.

Keys (units): ``force_offset`` [N], ``torque_offset`` [N·m],
``gravity_in_base`` [N, base frame], ``tool_weight`` [N], ``tool_mass`` [kg],
``center_of_mass`` [m, sensor frame], ``base_tilt_deg`` [U, V] in degrees,
``g`` [m/s²]; provenance: ``method``, ``pose_count``, ``sample_count``,
``residual_rms`` (per channel fx..mz [N, N·m], null without poses), ``urdf``, ``sensor_frame``,
``poses`` (ids, mean measured wrench and residual per pose), ``covariance``
(12×12 over ``[a, F0, M0, P]`` or null), ``std_errors`` (same keys as the
values), ``diagnostics`` (``ml`` only, else absent: noise used, chi-square,
per-pose normalized residuals, outliers, condition number, warnings; see
:class:`~ftkin.calibration.diagnostics.FitDiagnostics`), ``created`` (UTC, ISO 8601),
``ftkin_version``; ``kinematics`` (how the sensor frame was obtained: robot or URDF
path, its SHA-256, sensor parent and offset, see :class:`~ftkin.kinematics.record.KinematicsRecord`;
absent when unknown). Files without ``covariance``/``diagnostics`` (written by
``linear`` or an older ftkin) load with those set to None.

Floats are written with Python's shortest round-trip repr, so
save → load gives back the same numbers bit for bit.
"""

from __future__ import annotations

import datetime
import json
import math
from pathlib import Path

import numpy as np

from ..calibration.diagnostics import FitDiagnostics
from ..calibration.estimate import CalibrationResult
from ..exceptions import CalibrationFileError, FtkinError, InvalidInput
from ..kinematics.record import KinematicsRecord
from .atomic import atomic_write_text
from .calibration_checks import check_covariance, check_derived, has_bool, parse_calibration_json, short_repr

FORMAT_NAME = "ftkin-calibration"
FORMAT_VERSION = 1

UNITS = {
    "force_offset": "N, sensor frame",
    "torque_offset": "N*m, sensor frame",
    "gravity_in_base": "N, base frame",
    "tool_weight": "N",
    "tool_mass": "kg",
    "center_of_mass": "m, sensor frame",
    "base_tilt_deg": "deg, [U about base x, V about new y]",
    "g": "m/s^2",
    "residual_rms": "N (fx, fy, fz), N*m (mx, my, mz)",
}


def _jsonable(value):
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, dict):
        return {key: _jsonable(item) for key, item in value.items()}
    if isinstance(value, (np.floating, np.integer)):
        return value.item()
    return value


def _std_errors_document(result: CalibrationResult) -> dict | None:
    """Standard errors under the keys of the values (``base_tilt_deg`` in degrees; ``base_tilt`` kept, rad)."""
    errors = result.std_errors
    if errors is None:
        return None
    return {**errors, "base_tilt_deg": np.rad2deg(errors["base_tilt"])}


def calibration_to_dict(result: CalibrationResult) -> dict:
    """The JSON document of a calibration (plain Python types)."""
    from .._version import __version__

    document = {
        "format": FORMAT_NAME,
        "version": FORMAT_VERSION,
        "units": UNITS,
        "force_offset": result.force_offset,
        "torque_offset": result.torque_offset,
        "gravity_in_base": result.gravity_in_base,
        "tool_weight": result.tool_weight,
        "tool_mass": result.tool_mass,
        "center_of_mass": result.center_of_mass,
        "base_tilt_deg": list(result.base_tilt_deg),
        "g": result.g,
        "method": result.method,
        "pose_count": result.pose_count,
        "sample_count": result.sample_count,
        "residual_rms": result.residual_rms if result.pose_count else None,
        "urdf": result.urdf,
        "sensor_frame": result.sensor_frame,
        "poses": {
            "ids": result.pose_ids,
            "measured": result.pose_wrenches,
            "residuals": result.residuals,
        },
        "covariance": result.covariance,
        "std_errors": _std_errors_document(result),
        **({"diagnostics": result.diagnostics.to_dict()} if result.diagnostics is not None else {}),
        **({"kinematics": result.kinematics.to_dict()} if result.kinematics is not None else {}),
        "created": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
        "ftkin_version": __version__,
    }
    return _jsonable(document)


def save_calibration(result: CalibrationResult, path) -> Path:
    """Write a calibration file atomically (the old file survives a crash).

    Raises:
        InvalidInput: ``result`` is not a :class:`CalibrationResult`.
        CalibrationFileError: it holds NaN or infinite numbers.
    """
    if not isinstance(result, CalibrationResult):
        raise InvalidInput(
            f"result must be an ftkin.CalibrationResult (from calibrate or load_calibration), got {type(result).__name__}"
        )
    try:
        text = json.dumps(calibration_to_dict(result), indent=2, allow_nan=False) + "\n"
    except ValueError as error:  # NaN or infinity in a hand-built result
        raise CalibrationFileError(str(path), f"cannot write: {error}") from None
    return atomic_write_text(path, text)


class _Reader:
    """Typed access to a parsed document, raising CalibrationFileError with the key."""

    def __init__(self, path: str, document: dict):
        self.path, self.document = path, document

    def fail(self, message: str, key: str | None = None):
        raise CalibrationFileError(self.path, message, key)

    def get(self, key: str, required: bool = True):
        if key not in self.document:
            if required:
                self.fail("missing", key)
            return None
        return self.document[key]

    def optional(self, key: str, kind: type, default=None):
        """An optional value of JSON type ``kind`` (``str``, ``int``), ``default`` when absent or null."""
        value = self.get(key, required=False)
        if value is None:
            return default
        if isinstance(value, bool) or not isinstance(value, kind):
            self.fail(f"expected {kind.__name__} or null, got {short_repr(value)}", key)
        return value

    def count(self, key: str, default: int) -> int:
        """An optional non-negative integer count (``sample_count``, ``pose_count``)."""
        value = self.optional(key, int, default)
        if not 0 <= value <= 2**53:
            self.fail(f"expected a count between 0 and 2**53, got {short_repr(value)}", key)
        return value

    def array(self, key: str, shape: tuple, required: bool = True, source=None):
        value = self.get(key, required) if source is None else source
        if value is None:
            return None
        if has_bool(value):
            self.fail(f"expected numbers of shape {shape}, got a boolean (true/false are not numbers)", key)
        try:
            array = np.array(value, dtype=np.float64)
        except (TypeError, ValueError, OverflowError):
            self.fail(f"expected numbers of shape {shape}, got {short_repr(value)}", key)
        if array.shape != shape and not (array.size == 0 and 0 in shape):
            self.fail(f"expected shape {shape}, got {array.shape}", key)
        if not np.all(np.isfinite(array)):
            self.fail("contains NaN or infinite values", key)
        return array.reshape(shape)

    def number(self, key: str) -> float:
        value = self.get(key)
        try:
            finite = not isinstance(value, bool) and isinstance(value, (int, float)) and math.isfinite(value)
        except OverflowError:
            finite = False
        if not finite:
            self.fail(f"expected a finite number, got {short_repr(value)}", key)
        return float(value)


def _diagnostics(reader: _Reader) -> FitDiagnostics | None:
    data = reader.get("diagnostics", required=False)
    if data is None:
        return None
    if not isinstance(data, dict):
        reader.fail(f"expected an object, got {type(data).__name__}", "diagnostics")
    flags = [key for key, value in data.items() if has_bool(value)]
    if flags:
        reader.fail(f"{flags[0]!r} holds a boolean; true/false are not numbers", "diagnostics")
    try:
        return FitDiagnostics.from_dict(data)
    except KeyError as error:
        reader.fail(f"missing {error.args[0]!r}", "diagnostics")
    except (TypeError, ValueError, OverflowError, FtkinError) as error:
        reader.fail(f"malformed: {str(error)[:200]}", "diagnostics")


def _kinematics(reader: _Reader) -> KinematicsRecord | None:
    data = reader.get("kinematics", required=False)
    if data is None:
        return None
    try:
        return KinematicsRecord.from_dict(data)
    except FtkinError as error:
        reader.fail(f"malformed: {error}", "kinematics")


def calibration_from_dict(document, path: str = "<calibration>") -> CalibrationResult:
    """Rebuild a :class:`CalibrationResult` from a parsed calibration document."""
    if not isinstance(document, dict):
        raise CalibrationFileError(path, f"expected a JSON object, got {type(document).__name__}")
    reader = _Reader(path, document)
    if document.get("format") != FORMAT_NAME:
        reader.fail(f"not an ftkin calibration file (format {document.get('format')!r}, expected {FORMAT_NAME!r})", "format")
    version = document.get("version")
    if isinstance(version, bool) or not isinstance(version, int):
        reader.fail(f"expected an integer version, got {version!r}", "version")
    if version > FORMAT_VERSION:
        reader.fail(
            f"written by a newer ftkin (file format version {version}); this ftkin reads versions up to "
            f"{FORMAT_VERSION}: upgrade ftkin",
            "version",
        )
    if version < 1:
        reader.fail(f"unknown format version {version}", "version")
    poses = reader.get("poses", required=False) or {}
    if not isinstance(poses, dict):
        reader.fail("expected an object with ids, measured, residuals", "poses")
    raw_ids = poses.get("ids")
    if raw_ids is None:
        raw_ids = []
    if not isinstance(raw_ids, list) or not all(
        isinstance(i, int) and not isinstance(i, bool) and abs(i) <= 2**53 for i in raw_ids
    ):
        reader.fail(f"expected a list of integer pose ids of magnitude at most 2**53, got {short_repr(raw_ids)}", "poses.ids")
    pose_ids = np.array(raw_ids, dtype=np.int64)
    count = len(pose_ids)
    measured = reader.array("poses.measured", (count, 6), source=poses.get("measured", np.zeros((0, 6))))
    residuals = reader.array("poses.residuals", (count, 6), source=poses.get("residuals", np.zeros((0, 6))))
    method = reader.optional("method", str, "unknown")
    urdf, sensor_frame = reader.optional("urdf", str), reader.optional("sensor_frame", str)
    sample_count = reader.count("sample_count", count)
    if "pose_count" in document and reader.count("pose_count", count) != count:
        reader.fail(f"{document['pose_count']} disagrees with the {count} pose ids in poses.ids", "pose_count")
    try:
        result = CalibrationResult(
            force_offset=reader.array("force_offset", (3,)),
            torque_offset=reader.array("torque_offset", (3,)),
            gravity_in_base=reader.array("gravity_in_base", (3,)),
            center_of_mass=reader.array("center_of_mass", (3,)),
            g=reader.number("g"),
            method=method,
            pose_ids=pose_ids,
            pose_wrenches=measured,
            residuals=residuals,
            sample_count=sample_count,
            urdf=urdf,
            sensor_frame=sensor_frame,
            covariance=reader.array("covariance", (12, 12), required=False),
            diagnostics=_diagnostics(reader),
            kinematics=_kinematics(reader),
        )
    except (ValueError, TypeError) as error:
        raise CalibrationFileError(path, str(error)) from None
    if not (np.isfinite(result.tool_weight) and result.tool_weight > 0.0):
        reader.fail(f"|gravity_in_base| must be finite and positive, got {result.tool_weight}", "gravity_in_base")
    check_derived(reader, document, result)
    check_covariance(reader, result.covariance)
    return result


def load_calibration(path) -> CalibrationResult:
    """Read a calibration file.

    Raises:
        CalibrationFileError: missing file, not JSON (with line and column),
            another format, a newer version, or a missing or malformed key.
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise CalibrationFileError(str(path), "file not found") from None
    except IsADirectoryError:
        raise CalibrationFileError(str(path), "is a folder; expected a calibration JSON file") from None
    except (OSError, UnicodeDecodeError) as error:
        raise CalibrationFileError(str(path), f"cannot read: {error}") from None
    if not text.strip():
        raise CalibrationFileError(str(path), "file is empty; expected an ftkin calibration JSON document")
    return calibration_from_dict(parse_calibration_json(text, str(path)), str(path))
