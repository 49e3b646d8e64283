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
:class:`~ftkin.calibration.diagnostics.FitDiagnostics`), ``fit_test`` (every calibration kind
but ``linear``, the same fields: ``fit_name``, ``chi_square``, ``dof``, ``p_value`` or null with
``untested_reason``, ``verdict``, ``noise_source``, ``noise_dof``, ``channel_names`` with
``channel_chi_square``, ``outlier_kind`` with ``outliers`` (pose ids, or ``[start, end]`` time
spans [s]), ``condition_number``, ``parameter_count``; see
:class:`~ftkin.calibration.goodness_of_fit.FitTest`), ``created`` (UTC, ISO 8601),
``ftkin_version``; a dynamic calibration adds ``inertia`` (3×3 about the
centre of mass, sensor axes [kg·m²]) and ``std_errors.inertia`` and loads as a
:class:`~ftkin.calibration.dynamic.DynamicCalibrationResult`; ``imu`` (a
calibration from the sensor's IMU: :mod:`ftkin.io.imu_calibration_file`); ``kinematics``
(the arm: robot or URDF path, sensor parent and offset, and the chain from the base to the
sensor frame that arms are compared by, see :class:`~ftkin.kinematics.record.KinematicsRecord`;
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

Reading refuses duplicate JSON keys (which value is meant would be
ambiguous) and absurd nesting; the parameters must agree with the derived
fields written beside them (``tool_weight``, ``tool_mass``, ``base_tilt_deg``);
a covariance must be symmetric positive semi-definite; the units a file
states must be ftkin's; the parameters must be physically plausible (centre of
mass within 10 m of the sensor, bias and weight at most 1e6 N or N·m,
g between 1 and 30 m/s²). Booleans are not numbers. Each failure is a
:class:`~ftkin.exceptions.CalibrationFileError` naming the key. The ``drift``
entry's common keys are read here; each drift model reads its own
(:meth:`~ftkin.calibration.drift.DriftModel.to_document`), looked up by name in the drift
registry, so a registered model round-trips unchanged.
"""

import datetime
import json
import math
import os
from collections import Counter
from dataclasses import replace
from pathlib import Path

import numpy as np

from ..calibration.diagnostics import FitDiagnostics
from ..calibration.drift import BiasDrift, parse_drift
from ..calibration.dynamic import DynamicCalibrationResult
from ..calibration.goodness_of_fit import FIT_TEST_TYPES, FitTest
from ..calibration.log_cholesky import is_physically_consistent, parameters_from_body
from ..calibration.model import check_gravity
from ..calibration.result import CalibrationResult
from ..exceptions import CalibrationFileError, FtkinError, InvalidInput
from ..kinematics.record import KinematicsRecord
from ..kinematics.rotations import euler_zyx_to_matrix
from ..validation import MAX_WRENCH
from .atomic import atomic_write_text
from .json_reader import JsonReader, NestedReader, short_repr

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

MAX_COM_DISTANCE = 10.0
"""Farthest plausible centre of mass from the sensor [m] (the planner's bound too)."""


def _plain(value):
    """A numpy array or scalar as plain Python (the ``default`` of ``json.dumps``)."""
    if isinstance(value, (np.ndarray, np.generic)):
        return value.tolist()
    raise TypeError(f"Object of type {type(value).__name__} is not JSON serializable")


def _std_errors_document(result: CalibrationResult) -> dict | None:
    """Standard errors under the keys of the values (``base_tilt_deg`` in degrees; ``base_tilt``
    kept, rad).
    """
    errors, inertia = result.std_errors, result.inertia_std_errors
    if errors is None:
        return None
    return {
        **errors,
        "base_tilt_deg": np.rad2deg(errors["base_tilt"]),
        **({} if inertia is None else {"inertia": inertia}),
    }


def _drift_document(drift: BiasDrift | None) -> dict | None:
    """The ``drift`` entry of a calibration file (None without a trajectory)."""
    if drift is None:
        return None
    return {
        "model": drift.model,
        "selected_by": drift.selected_by,
        "times": drift.times,
        "bias": drift.bias,
        "bias_std": drift.bias_std,
        **drift.kind.to_document(drift),
        "time_scale": drift.time_scale,
        "criteria": {name: float(value) for name, value in drift.criteria.items()},
        "recorded_span": drift.recorded_span,
    }


def calibration_to_dict(result: CalibrationResult) -> dict:
    """The JSON document of a calibration (plain Python types)."""
    from .._version import __version__

    inertia = result.inertia_about_com_in_sensor  # a dynamic calibration's, 3×3 [kg·m²]
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
        **({} if inertia is None else {"inertia": inertia}),
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
        **({"fit_test": result.fit_test.to_dict()} if result.fit_test is not None else {}),
        "drift": _drift_document(result.drift),
        **({"kinematics": result.kinematics.to_dict()} if result.kinematics is not None else {}),
        **_imu_document(result),  # a calibration from the IMU: R_SI, accelerometer bias, ...
        "created": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
        "ftkin_version": __version__,
    }
    return json.loads(json.dumps(document, default=_plain))


def _imu_document(result) -> dict:
    """The ``imu`` entry of a calibration from the IMU (:mod:`ftkin.io.imu_calibration_file`,
    imported when a file is written, not with this module)."""
    from .imu_calibration_file import imu_document

    return imu_document(result)


def save_calibration(result: CalibrationResult, path, *, rezero: dict | None = None) -> Path:
    """Write a calibration file atomically (the old file survives a crash).

    ``rezero``: a record of the re-zero that produced this bias, stored under
    ``rezero`` (informative; see ``ftkin rezero``).

    Raises:
        InvalidInput: ``result`` is not a :class:`CalibrationResult`.
        CalibrationFileError: it holds NaN or infinite numbers, or parameters no
            tool has (see the module docstring).
    """
    if not isinstance(result, CalibrationResult):
        raise InvalidInput(
            "result must be an ftkin.CalibrationResult (from calibrate or load_calibration), got "
            f"{type(result).__name__}"
        )
    _check_plausible(JsonReader(str(path), {}), result)  # never write what loading would refuse
    try:
        document = calibration_to_dict(result)
        if rezero is not None:
            document["rezero"] = rezero
        text = json.dumps(document, indent=2, allow_nan=False, default=_plain) + "\n"
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


def _part(reader: JsonReader, key: str, from_dict, types: dict | None = None):
    """The optional object ``key`` rebuilt by ``from_dict`` (None when absent or null), its
    entries first checked against ``types`` (see :meth:`JsonReader.check_types`).
    """
    data = reader.optional_object(key)
    if data is None:
        return None
    if types is not None:
        NestedReader(reader.path, data, key).check_types(types)
    try:
        return from_dict(data)
    except KeyError as error:
        reader.fail(f"missing {error.args[0]!r}", key)
    except (TypeError, ValueError, OverflowError, FtkinError) as error:
        reader.fail(f"malformed: {str(error)[:200]}", key)


def _drift(reader: JsonReader) -> BiasDrift | None:
    """The :class:`BiasDrift` of the ``drift`` entry (None when absent or null)."""
    data = reader.optional_object("drift")
    if data is None:
        return None
    sub = NestedReader(reader.path, data, "drift")
    try:
        kind = parse_drift(sub.get("model"))
    except InvalidInput as error:
        reader.fail(str(error), "drift.model")
    times = sub.array("times", (len(data["times"]) if isinstance(data.get("times"), list) else 0,))
    count = len(times)
    criteria = data.get("criteria") or {}
    if not isinstance(criteria, dict):
        reader.fail("expected an object of numbers", "drift.criteria")
    NestedReader(reader.path, criteria, "drift.criteria").check_types(
        dict.fromkeys(criteria, "number")
    )
    try:
        return BiasDrift(
            model=kind.name,
            selected_by=sub.optional("selected_by", str, "given"),
            times=times,
            bias=sub.array("bias", (count, 6)),
            bias_std=sub.array("bias_std", (count, 6)),
            time_scale=sub.number("time_scale") if "time_scale" in data else 1.0,
            criteria={str(name): float(value) for name, value in criteria.items()},
            recorded_span=sub.array("recorded_span", (2,), required=False),
            **kind.from_document(sub),
        )
    except (FtkinError, TypeError, ValueError) as error:
        reader.fail(f"malformed: {error}", "drift")


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


def _with_inertia(reader, result: CalibrationResult, inertia: np.ndarray) -> CalibrationResult:
    """The :class:`~ftkin.calibration.dynamic.DynamicCalibrationResult` of a file with an
    ``inertia``.
    """
    if not np.allclose(
        inertia, inertia.T, rtol=0.0, atol=1e-12 * max(1.0, float(np.abs(inertia).max()))
    ):
        reader.fail("the inertia must be a symmetric 3×3 matrix [kg·m²]", "inertia")
    errors = NestedReader(reader.path, reader.optional_object("std_errors") or {}, "std_errors")
    inertia_errors = errors.array("inertia", (3, 3), required=False)
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
    return DynamicCalibrationResult(**{**result.base_fields(), **inertia_fields})


def calibration_from_dict(document, path: str = "<calibration>") -> CalibrationResult:
    """Rebuild a :class:`CalibrationResult` from a parsed calibration document."""
    if not isinstance(document, dict):
        raise CalibrationFileError(path, f"expected a JSON object, got {type(document).__name__}")
    reader = JsonReader(path, document)
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
            diagnostics=_part(reader, "diagnostics", FitDiagnostics.from_dict, DIAGNOSTICS_TYPES),
            fit_test=_part(reader, "fit_test", FitTest.from_dict, FIT_TEST_TYPES),
            drift=_drift(reader),
            kinematics=_part(reader, "kinematics", KinematicsRecord.from_dict),
            **poses,
            **mount,
        )
    except (ValueError, TypeError) as error:
        raise CalibrationFileError(path, str(error)) from None
    if result.diagnostics is not None and result.fit_test is not None:  # as the fit made them
        result = replace(result, diagnostics=replace(result.diagnostics, fit_test=result.fit_test))
    if not (np.isfinite(result.tool_weight) and result.tool_weight > 0.0):
        reader.fail(
            f"|gravity_in_base| must be finite and positive, got {result.tool_weight}",
            "gravity_in_base",
        )
    _check_consistent(reader, document, result)
    _check_plausible(reader, result)
    result = result if inertia is None else _with_inertia(reader, result, inertia)
    if "imu" not in document:
        return result
    from .imu_calibration_file import imu_result  # the IMU's entry: its types load on demand

    return imu_result(reader, result)


def _check_consistent(reader, document: dict, result) -> None:
    """Refuse a document that disagrees with itself: a derived field (``tool_weight``,
    ``tool_mass``, ``base_tilt_deg``) that disagrees with the parameters, ``units`` naming another
    unit than ftkin's for a key (e.g. ``"force_offset": "kN"``), or a covariance that is not
    symmetric positive semi-definite.
    """
    derived = (
        ("tool_weight", result.tool_weight, "N", "|gravity_in_base|"),
        ("tool_mass", result.tool_mass, "kg", "|gravity_in_base| / g"),
    )
    for key, value, unit, source in derived:
        if key in document:
            stated = reader.number(key)
            if not math.isclose(stated, value, rel_tol=1e-9, abs_tol=1e-12):
                reader.fail(
                    f"{stated} {unit} disagrees with {source} = {value} {unit} (file edited by "
                    "hand?)",
                    key,
                )
    if "base_tilt_deg" in document:
        stated = reader.array("base_tilt_deg", (2,))
        expected = np.array(result.base_tilt_deg)
        if not np.allclose(stated, expected, rtol=1e-9, atol=1e-9):
            reader.fail(
                f"{stated.tolist()} deg disagrees with the tilt of gravity_in_base = "
                f"{expected.tolist()} deg "
                "(file edited by hand?)",
                "base_tilt_deg",
            )

    def turn_deg(rotation) -> float:  # the angle of a rotation [deg]
        return float(np.rad2deg(np.arccos(np.clip((np.trace(rotation) - 1.0) / 2.0, -1.0, 1.0))))

    if "mount_rpy_deg" in document:  # compared as rotations: a yaw of 180° is one of -180°
        stated = reader.array("mount_rpy_deg", (3,))
        roll, pitch, yaw = np.deg2rad(stated)
        from_rpy = euler_zyx_to_matrix([yaw, pitch, roll])
        if turn_deg(from_rpy.T @ result.mount_rotation) > 1e-6:
            reader.fail(
                f"{stated.tolist()} deg disagrees with mount_rotation, whose roll-pitch-yaw is "
                f"{np.round(result.mount_rpy_deg, 9).tolist()} deg (file edited by hand?)",
                "mount_rpy_deg",
            )
    turn = turn_deg(result.mount_rotation)
    if result.mount_mode == "none" and turn > 1e-6:
        reader.fail(
            f"mount_mode 'none' but mount_rotation turns the sensor by {turn:.4g}°: a mount is "
            "only applied when it was estimated (mount_mode 'yaw' or 'full'; file edited by hand?)",
            "mount_rotation",
        )
    stated_units = reader.optional_object("units") or {}
    for key, our_unit in UNITS.items():
        if key in stated_units and key in document:
            value = stated_units[key]
            unit, ours = (str(value).split(",")[0].strip(), our_unit.split(",")[0].strip())
            if not isinstance(value, str) or unit.replace("·", "*") != ours:
                reader.fail(
                    f"{key} is stated in {short_repr(value)}, but ftkin files are in {ours!r} "
                    "(convert the values, or the file is not ftkin's)",
                    "units",
                )
    covariance = result.covariance
    if covariance is not None:
        scale = max(float(np.max(np.abs(covariance))), 1e-300)
        asymmetry = float(np.max(np.abs(covariance - covariance.T)))
        if asymmetry > 1e-9 * scale:
            reader.fail(
                f"not symmetric (largest |C - C^T| = {asymmetry:.3g}); expected a covariance "
                "matrix",
                "covariance",
            )
        smallest = float(np.linalg.eigvalsh(0.5 * (covariance + covariance.T))[0])
        if smallest < -1e-9 * scale:
            reader.fail(
                f"not positive semi-definite (eigenvalue {smallest:.3g}); expected a covariance "
                "matrix",
                "covariance",
            )


def _check_plausible(reader, result) -> None:
    """Refuse parameters no tool on a wrist sensor has: a wrong unit or a corrupt file that still
    parses.
    """
    distance = float(np.linalg.norm(result.center_of_mass))
    if distance > MAX_COM_DISTANCE:
        reader.fail(
            f"the centre of mass is {distance:.4g} m from the sensor; expected at most "
            f"{MAX_COM_DISTANCE:g} m "
            "(millimetres written as metres?)",
            "center_of_mass",
        )
    for key, value in (
        ("force_offset", result.force_offset),
        ("torque_offset", result.torque_offset),
        ("gravity_in_base", result.gravity_in_base),
    ):
        if float(np.max(np.abs(value))) > MAX_WRENCH:  # the samples reader's bound on a reading
            reader.fail(
                f"{np.asarray(value).tolist()} is beyond ±{MAX_WRENCH:g} (N or N·m): not a load",
                key,
            )
    try:
        check_gravity(result.g)
    except InvalidInput as error:
        reader.fail(f"{error} (Earth: 9.80665)", "g")


def load_calibration(path) -> CalibrationResult:
    """Read a calibration file.

    Raises:
        CalibrationFileError: missing file, not JSON (with line and column),
            another format, a newer version, or a missing or malformed key.
    """
    if not isinstance(path, (str, os.PathLike)) or isinstance(path, bytes):
        raise CalibrationFileError(
            repr(path),
            "expected a calibration file's path (a str or a pathlib.Path), got "
            f"{type(path).__name__}",
        )
    path = Path(path)
    source = str(path)

    def unique_keys(pairs):  # which of two values under one key is meant would be ambiguous
        repeated = [key for key, count in Counter(key for key, _ in pairs).items() if count > 1]
        if repeated:
            raise CalibrationFileError(
                source,
                "duplicate key in a JSON object: which value is meant is ambiguous",
                repeated[0],
            )
        return dict(pairs)

    try:
        text = path.read_text(encoding="utf-8")
        if not text.strip():
            raise CalibrationFileError(
                source, "file is empty; expected an ftkin calibration JSON document"
            )
        document = json.loads(text, object_pairs_hook=unique_keys)
    except FileNotFoundError:
        raise CalibrationFileError(source, "file not found") from None
    except IsADirectoryError:
        raise CalibrationFileError(
            source, "is a folder; expected a calibration JSON file"
        ) from None
    except json.JSONDecodeError as error:
        raise CalibrationFileError(
            source,
            f"not valid JSON (truncated or corrupt?) at line {error.lineno}, column {error.colno}: "
            f"{error.msg}",
        ) from None
    except (OSError, UnicodeDecodeError) as error:
        raise CalibrationFileError(source, f"cannot read: {error}") from None
    except RecursionError:
        raise CalibrationFileError(
            source, "JSON nested too deeply; expected an ftkin calibration document"
        ) from None
    except ValueError as error:  # a number with too many digits
        raise CalibrationFileError(source, f"not a valid calibration document: {error}") from None
    return calibration_from_dict(document, source)
