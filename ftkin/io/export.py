"""Export a calibration: the registry of formats and the entry points.

Every format, ROS controller parameters (:mod:`ftkin.io.ros_controllers`) and robot payloads
(:mod:`ftkin.io.payload_export`) alike, is an :class:`~ftkin.io.export_format.ExportFormat`
registered here by name; ``ftkin export --format`` offers :data:`EXPORT_FORMATS` and each
format's own options. A new format is one module plus one line in :data:`_BUILT_IN` (or a
:func:`register_export_format` call from anywhere).

Before anything is written, :func:`export_request` checks the options (names written into the
file against ROS's rules) and, when an arm is given, that it is the arm the calibration was made
with (its kinematics record), as :class:`~ftkin.control.compensation.Compensator` does; a
sensor offset recorded at calibration but missing from the arm is named, since the payload's
centre of mass would be off by that offset.
"""

from pathlib import Path

import numpy as np

from ..calibration.result import CalibrationResult
from ..exceptions import InvalidInput
from .atomic import atomic_write_text
from .export_format import ExportFormat, ExportRequest
from .payload_export import FrankaLoadExport, UrPayloadExport
from .ros_controllers import AdmittanceExport, FtCalibExport, GravityCompensationExport

EXPORT_FORMATS: dict[str, ExportFormat] = {}
"""The registered formats by name, in ``--help`` order."""


def register_export_format(export_format: ExportFormat, *, replace: bool = False) -> ExportFormat:
    """Add ``export_format`` to :data:`EXPORT_FORMATS` (``replace``: over one of the same name).

    Raises:
        InvalidInput: not an :class:`ExportFormat` instance, or its name is taken.
    """
    if not isinstance(export_format, ExportFormat):
        raise InvalidInput(
            f"an export format must be an ExportFormat instance, got {type(export_format).__name__}"
        )
    if export_format.name in EXPORT_FORMATS and not replace:
        raise InvalidInput(f"export format {export_format.name!r} is already registered")
    EXPORT_FORMATS[export_format.name] = export_format
    return export_format


_BUILT_IN = (
    AdmittanceExport(),
    GravityCompensationExport(),
    FtCalibExport(),
    FrankaLoadExport(),
    UrPayloadExport(),
)
for _format in _BUILT_IN:
    register_export_format(_format)


def export_format(name: str) -> ExportFormat:
    """The registered format ``name``, or InvalidInput listing the known ones."""
    if name not in EXPORT_FORMATS:
        raise InvalidInput(
            f"unknown export format {name!r}; expected one of {', '.join(EXPORT_FORMATS)}"
        )
    return EXPORT_FORMATS[name]


def recorded_arm(calibration):
    """The arm ``calibration`` records, rebuilt
    (:meth:`~ftkin.kinematics.record.KinematicsRecord.build_arm`), or None when it records none:
    the default wherever an arm is optional.

    Raises:
        InvalidInput: the record cannot be rebuilt (its URDF is gone or its kinematics changed).
    """
    record = CalibrationResult.from_model(calibration).kinematics
    return None if record is None else record.build_arm()


def arm_problems(calibration, arm) -> list[str]:
    """How ``arm`` differs from the arm ``calibration`` was made with (empty: the same
    kinematics, :meth:`~ftkin.kinematics.record.KinematicsRecord.mismatches`, or no record); when
    they differ, another robot name and a sensor offset the arm lacks come first, with the error
    it would cause.
    """
    record = CalibrationResult.from_model(calibration).kinematics
    differences = [] if record is None else record.mismatches(arm)
    if not differences:
        return []
    problems = []
    if record.robot is not None and arm.robot_name not in (None, record.robot):
        problems.append(f"robot {arm.robot_name!r}, calibrated with {record.robot!r}")
    if record.sensor_offset is not None:
        mount = arm.sensor_mount
        given = np.zeros(6) if mount is None else np.array([*mount.translation, *mount.rpy])
        if not np.allclose(given, record.sensor_offset, atol=1e-9):
            shift = np.linalg.norm(given[:3] - np.asarray(record.sensor_offset[:3]))
            problems.append(
                "the calibration recorded the sensor offset --sensor-offset "
                + " ".join(f"{value:g}" for value in record.sensor_offset)
                + f" on {record.sensor_parent}, this arm has "
                + " ".join(f"{value:g}" for value in given)
                + f": the centre of mass would be off by {shift * 1e3:.1f} mm"
            )
    return problems + differences


def export_request(
    calibration, fmt: str, arm=None, *, path=None, allow_other_arm: bool = False, **options
) -> tuple[ExportFormat, ExportRequest]:
    """The format ``fmt`` and a checked request: options known and valid, the arm the right one.

    Raises:
        InvalidInput: unknown format or option, an invalid ROS name, a format that needs an arm
            without one, or an arm other than the calibration's (unless ``allow_other_arm``).
    """
    chosen = export_format(fmt)
    known = {option.name: option for option in chosen.options}
    given = {name: value for name, value in options.items() if value is not None}
    unknown = sorted(set(given) - set(known))
    if unknown:
        takers: dict[str, list[str]] = {}
        for other in EXPORT_FORMATS.values():
            for option in other.options:
                takers.setdefault(option.name, [option.flag]).append(other.name)
        named = [
            f"{name} ({takers[name][0]}: --format {', '.join(takers[name][1:])})"
            if name in takers
            else name
            for name in unknown
        ]
        takes = [f"{name} ({option.flag})" for name, option in known.items()]
        raise InvalidInput(
            f"{fmt} takes no {', '.join(named)}; its options: {', '.join(takes) or 'none'}"
        )
    if chosen.needs_arm and arm is None:
        arm = recorded_arm(calibration)  # the calibration's own arm, when it records one
    if chosen.needs_arm and arm is None:
        raise InvalidInput(
            f"{fmt} needs the arm (the centre of mass is written in its flange) and this "
            "calibration records none: pass arm= (ftkin export: --robot NAME or --urdf PATH)"
        )
    problems = [] if arm is None or allow_other_arm else arm_problems(calibration, arm)
    if problems:
        record = CalibrationResult.from_model(calibration).kinematics.describe()
        raise InvalidInput(
            f"this arm is not the one the calibration was made with ({record}): "
            + "; ".join(problems)
            + ". Pass allow_other_arm=True (ftkin export: --allow-other-arm) if that is deliberate."
        )
    checked = {name: known[name].check(value) for name, value in given.items()}
    return chosen, ExportRequest(calibration, arm, checked, None if path is None else Path(path))


def export_text(calibration, fmt: str, arm=None, **options) -> str:
    """The file text of ``calibration`` in format ``fmt`` (keywords: :func:`export_request`)."""
    chosen, request = export_request(calibration, fmt, arm, **options)
    return chosen.text(request)


def export_notes(calibration, fmt: str, arm=None, **options) -> list[str]:
    """What ``fmt`` cannot represent about ``calibration``, one sentence each."""
    chosen, request = export_request(calibration, fmt, arm, **options)
    return chosen.notes(request)


def export_calibration(calibration, path, fmt: str, arm=None, **options) -> Path:
    """Write :func:`export_text` to ``path`` atomically (checked first); returns the path."""
    return atomic_write_text(Path(path), export_text(calibration, fmt, arm, path=path, **options))


def export_payload(calibration, arm, path, fmt: str, flange_frame=None, inertia=None, **bodies):
    """Write a payload format (``franka-load``, ``ur-payload``; ``.script``: URScript only).

    ``bodies``: ``end_effector=`` and ``sensor_body=`` (``franka-load``; flange-frame
    :class:`~ftkin.io.payload_inertia.RigidBody`): write ``measured − end_effector +
    sensor_body``, the load for a controller that already models the end effector; and
    ``held_load=`` (both formats; a :class:`~ftkin.io.payload_held_load.HeldLoad` or its JSON
    file): a load the gripper holds, added to the tool as one rigid body.
    """
    return export_calibration(
        calibration, path, fmt, arm, flange_frame=flange_frame, inertia=inertia, **bodies
    )
