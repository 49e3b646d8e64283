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
``ftkin_version``; a dynamic calibration adds ``inertia`` (3×3 about the
centre of mass, sensor axes [kg·m²]) and ``std_errors.inertia`` and loads as a
:class:`~ftkin.calibration.dynamic.DynamicCalibrationResult`; ``kinematics``
(how the sensor frame was obtained: robot or URDF path, its SHA-256, sensor
parent and offset, see :class:`~ftkin.kinematics.record.KinematicsRecord`;
absent when unknown). Files without ``covariance``/``diagnostics`` (written by
``linear`` or an older ftkin) load with those set to None.

The sensor as it is really mounted (:mod:`ftkin.calibration.mount`,
:mod:`ftkin.calibration.conventions`): ``mount_rotation`` (3×3 ``R_M``, URDF
sensor frame → real sensor frame), ``mount_rpy_deg`` (its roll, pitch, yaw
[deg], for reading), ``mount_mode``, ``mount_covariance`` (k×k [rad²] or
null), ``sensor_sign`` (+1 or −1) and ``flip_axis`` (null, "x", "y", "z").
Files without them load with the identity mount, sign +1 and no flip.

Format version 2 adds ``drift`` (null when the samples had no times): the bias
trajectory of :class:`~ftkin.calibration.drift.BiasDrift`, ``model``,
``selected_by``, ``times`` [s], ``bias`` and ``bias_std`` (one ``[F0, M0]``
row per time [N, N·m]), ``rate`` [N/√s, N·m/√s] or null, ``coefficients`` and
``time_scale`` [s] of a polynomial or null, ``criteria`` (BIC per candidate),
``recorded_span`` (first and last reading time [s]);
and ``rezero`` (absent, or the last re-zero: ``q`` [rad] or ``rotation``,
``wrench``, ``previous_bias``, ``time``; informative, written by ``ftkin
rezero`` and not read back). Version 1 files load with ``drift`` None.

Floats are written with Python's shortest round-trip repr, so
save → load gives back the same numbers bit for bit.
"""

from __future__ import annotations

import datetime
import json
from pathlib import Path

import numpy as np

from ..calibration.diagnostics import FitDiagnostics
from ..calibration.dynamic import DynamicCalibrationResult
from ..calibration.estimate import CalibrationResult
from ..calibration.log_cholesky import is_physically_consistent, parameters_from_body
from ..exceptions import CalibrationFileError, FtkinError, InvalidInput
from ..kinematics.record import KinematicsRecord
from .atomic import atomic_write_text
from .calibration_checks import (
    check_document,
    check_plausible,
    parse_calibration_json,
    short_repr,
)
from .drift_file import drift_from_document, drift_to_document
from .json_reader import JsonReader, NestedReader

FORMAT_NAME = "ftkin-calibration"
FORMAT_VERSION = 2

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
    "mount_rotation": "URDF sensor frame -> real sensor frame; real R_BS = R_BS_urdf * "
    "mount_rotation^T",
    "mount_rpy_deg": "deg, roll-pitch-yaw of mount_rotation (R = Rz(yaw) Ry(pitch) Rx(roll))",
    "sensor_sign": "+1: readings are the load on the sensor, -1: the reaction (all readings "
    "negated)",
    "flip_axis": "sensor axis whose force and torque channels are "
    "negated in every reading, or null",
    "inertia": "kg*m^2, about the centre of mass, sensor axes",
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
    """Standard errors under the keys of the values (``base_tilt_deg`` in degrees; ``base_tilt``
    kept, rad).
    """
    errors = result.std_errors
    if errors is None:
        return None
    document = {**errors, "base_tilt_deg": np.rad2deg(errors["base_tilt"])}
    if result.inertia_std_errors is not None:
        document["inertia"] = result.inertia_std_errors
    return document


def inertia_document(result: CalibrationResult) -> dict:
    """``inertia`` (3×3 about the COM, sensor axes [kg·m²]) of a dynamic calibration, else
    nothing.
    """
    return (
        {}
        if result.inertia_about_com_in_sensor is None
        else {"inertia": result.inertia_about_com_in_sensor}
    )


def with_inertia(reader, result: CalibrationResult, inertia: np.ndarray) -> CalibrationResult:
    """The :class:`~ftkin.calibration.dynamic.DynamicCalibrationResult` of a file with an
    ``inertia``.
    """
    if not np.allclose(
        inertia, inertia.T, rtol=0.0, atol=1e-12 * max(1.0, float(np.abs(inertia).max()))
    ):
        reader.fail("the inertia must be a symmetric 3×3 matrix [kg·m²]", "inertia")
    errors = reader.get("std_errors", required=False)
    inertia_errors = None
    if isinstance(errors, dict) and errors.get("inertia") is not None:
        inertia_errors = reader.array("std_errors.inertia", (3, 3), source=errors["inertia"])
    theta = parameters_from_body(result.tool_mass, result.center_of_mass, inertia)
    if not is_physically_consistent(theta, tolerance=-1e-12):
        reader.fail(
            "the inertia is not physically consistent with the mass and centre of mass (a "
            "principal moment "
            "is negative or violates the triangle inequality)",
            "inertia",
        )
    inertia_fields = {
        "inertia_about_com_in_sensor": inertia,
        "inertia_std_errors": inertia_errors,
        "inertial_parameters": theta,
    }
    return DynamicCalibrationResult(**{**vars(result), **inertia_fields})


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
        **inertia_document(result),
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
        "mount_rotation": result.mount_rotation,
        "mount_rpy_deg": result.mount_rpy_deg,
        "mount_mode": result.mount_mode,
        "mount_covariance": result.mount_covariance,
        "mount_std_deg": result.mount_std_deg,
        "sensor_sign": result.sensor_sign,
        "flip_axis": result.flip_axis,
        **({"diagnostics": result.diagnostics.to_dict()} if result.diagnostics is not None else {}),
        "drift": drift_to_document(result.drift),
        **({"kinematics": result.kinematics.to_dict()} if result.kinematics is not None else {}),
        "created": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
        "ftkin_version": __version__,
    }
    return _jsonable(document)


def save_calibration(result: CalibrationResult, path, *, rezero: dict | None = None) -> Path:
    """Write a calibration file atomically (the old file survives a crash).

    ``rezero``: a record of the re-zero that produced this bias, stored under
    ``rezero`` (informative; see ``ftkin rezero``).

    Raises:
        InvalidInput: ``result`` is not a :class:`CalibrationResult`.
        CalibrationFileError: it holds NaN or infinite numbers, or parameters no
            tool has (:func:`~ftkin.io.calibration_checks.check_plausible`).
    """
    if not isinstance(result, CalibrationResult):
        raise InvalidInput(
            "result must be an ftkin.CalibrationResult (from calibrate or load_calibration), got "
            f"{type(result).__name__}"
        )
    check_plausible(
        JsonReader(str(path), {}), result
    )  # never write what load_calibration would refuse
    try:
        document = calibration_to_dict(result)
        if rezero is not None:
            document["rezero"] = _jsonable(rezero)
        text = json.dumps(document, indent=2, allow_nan=False) + "\n"
    except ValueError as error:  # NaN or infinity in a hand-built result
        raise CalibrationFileError(str(path), f"cannot write: {error}") from None
    return atomic_write_text(path, text)


DIAGNOSTICS_TYPES = {
    **dict.fromkeys(("loss", "noise_source"), "string"),
    **dict.fromkeys(("noise_dof", "chi_square", "p_value", "covariance_scale"), "number?"),
    **dict.fromkeys(("condition_number",), "number?"),
    **dict.fromkeys(("noise_force_std", "noise_torque_std", "channel_chi_square"), "numbers?"),
    **dict.fromkeys(("pose_normalized_residuals", "pose_p_values"), "numbers?"),
    **dict.fromkeys(("weakest_direction", "relative_std_errors"), "numbers?"),
    **dict.fromkeys(("pose_ids", "outlier_pose_ids", "dropped_pose_ids"), "integers"),
    "dof": "integer",
    "warnings": "strings",
}
"""The JSON kind of each ``diagnostics`` key (see ``JsonReader.check_types``)."""


DOCUMENT_TYPES = {
    **dict.fromkeys(("created", "ftkin_version"), "string"),
    **dict.fromkeys(("residual_rms", "mount_rpy_deg"), "numbers?"),
}
"""The JSON kind of the keys written for people (read back only to be checked)."""


def _diagnostics(reader: JsonReader) -> FitDiagnostics | None:
    data = reader.optional_object("diagnostics")
    if data is None:
        return None
    NestedReader(reader.path, data, "diagnostics").check_types(DIAGNOSTICS_TYPES)
    try:
        return FitDiagnostics.from_dict(data)
    except KeyError as error:
        reader.fail(f"missing {error.args[0]!r}", "diagnostics")
    except (TypeError, ValueError, OverflowError, FtkinError) as error:
        reader.fail(f"malformed: {str(error)[:200]}", "diagnostics")


def _kinematics(reader: JsonReader) -> KinematicsRecord | None:
    data = reader.optional_object("kinematics")
    if data is None:
        return None
    try:
        return KinematicsRecord.from_dict(data)
    except FtkinError as error:
        reader.fail(f"malformed: {error}", "kinematics")


def _check_version(reader: JsonReader, document: dict) -> None:
    """Refuse another format, or a version this ftkin does not read."""
    if document.get("format") != FORMAT_NAME:
        reader.fail(
            f"not an ftkin calibration file (format {document.get('format')!r}, expected "
            f"{FORMAT_NAME!r})",
            "format",
        )
    reader.version(FORMAT_VERSION)
    reader.check_types(DOCUMENT_TYPES)
    for name in ("std_errors", "mount_std_deg"):  # objects of numbers
        numbers = reader.optional_object(name) or {}
        NestedReader(reader.path, numbers, name).check_types(dict.fromkeys(numbers, "numbers?"))


def _poses(reader: JsonReader, document: dict) -> dict:
    """The per-pose fields (``pose_ids``, ``pose_wrenches``, ``residuals``, ``sample_count``)."""
    poses = reader.get("poses", required=False) or {}
    if not isinstance(poses, dict):
        reader.fail("expected an object with ids, measured, residuals", "poses")
    raw_ids = poses.get("ids")
    raw_ids = [] if raw_ids is None else raw_ids
    if not isinstance(raw_ids, list) or not all(
        isinstance(i, int) and not isinstance(i, bool) and abs(i) <= 2**53 for i in raw_ids
    ):
        reader.fail(
            "expected a list of integer pose ids of magnitude at most 2**53, got "
            f"{short_repr(raw_ids)}",
            "poses.ids",
        )
    count = len(raw_ids)
    if "pose_count" in document and reader.count("pose_count", count) != count:
        reader.fail(
            f"{document['pose_count']} disagrees with the {count} pose ids in poses.ids",
            "pose_count",
        )
    return {
        "pose_ids": np.array(raw_ids, dtype=np.int64),
        "pose_wrenches": reader.array(
            "poses.measured", (count, 6), source=poses.get("measured", np.zeros((0, 6)))
        ),
        "residuals": reader.array(
            "poses.residuals", (count, 6), source=poses.get("residuals", np.zeros((0, 6)))
        ),
        "sample_count": reader.count("sample_count", count),
    }


def _mount(reader: JsonReader) -> dict:
    """The real sensor's fields: mount (identity when absent), its covariance, sign and flip."""
    mount = reader.array("mount_rotation", (3, 3), required=False)
    mode = reader.optional("mount_mode", str, "none")
    size = {"yaw": 1, "full": 3}.get(mode, 0)
    return {
        "mount_rotation": np.eye(3) if mount is None else mount,
        "mount_mode": mode,
        "mount_covariance": (
            reader.array("mount_covariance", (size, size), required=False) if size else None
        ),
        "sensor_sign": reader.optional("sensor_sign", int, 1),
        "flip_axis": reader.optional("flip_axis", str),
    }


def calibration_from_dict(document, path: str = "<calibration>") -> CalibrationResult:
    """Rebuild a :class:`CalibrationResult` from a parsed calibration document."""
    if not isinstance(document, dict):
        raise CalibrationFileError(path, f"expected a JSON object, got {type(document).__name__}")
    reader = JsonReader(path, document)
    _check_version(reader, document)
    poses = _poses(reader, document)
    mount = _mount(reader)
    inertia = reader.array("inertia", (3, 3), required=False)
    try:
        result = CalibrationResult(
            force_offset=reader.array("force_offset", (3,)),
            torque_offset=reader.array("torque_offset", (3,)),
            gravity_in_base=reader.array("gravity_in_base", (3,)),
            center_of_mass=reader.array("center_of_mass", (3,)),
            g=reader.number("g"),
            method=reader.optional("method", str, "unknown"),
            urdf=reader.optional("urdf", str),
            sensor_frame=reader.optional("sensor_frame", str),
            covariance=reader.array("covariance", (12, 12), required=False),
            diagnostics=_diagnostics(reader),
            drift=drift_from_document(reader),
            kinematics=_kinematics(reader),
            **poses,
            **mount,
        )
    except (ValueError, TypeError) as error:
        raise CalibrationFileError(path, str(error)) from None
    if not (np.isfinite(result.tool_weight) and result.tool_weight > 0.0):
        reader.fail(
            f"|gravity_in_base| must be finite and positive, got {result.tool_weight}",
            "gravity_in_base",
        )
    check_document(reader, document, result, UNITS)
    return result if inertia is None else with_inertia(reader, result, inertia)


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
        raise CalibrationFileError(
            str(path), "is a folder; expected a calibration JSON file"
        ) from None
    except (OSError, UnicodeDecodeError) as error:
        raise CalibrationFileError(str(path), f"cannot read: {error}") from None
    if not text.strip():
        raise CalibrationFileError(
            str(path), "file is empty; expected an ftkin calibration JSON document"
        )
    return calibration_from_dict(parse_calibration_json(text, str(path)), str(path))
