"""Exceptions raised by ftkin.

Every error ftkin raises on purpose derives from :class:`FtkinError`, so a
caller (a control loop, a CLI) can catch one type. Subclasses carry the data a
program needs to react (the unknown name, the list of valid ones, ...), and
their message says what was wrong and what was expected.

Errors from numpy, Pinocchio or the file system are wrapped at ftkin's
boundary; they should never reach a user as a bare traceback.
"""

from collections.abc import Sequence
from pathlib import Path


class FtkinError(Exception):
    """Base class of every error ftkin raises on purpose."""


class InvalidInput(FtkinError, ValueError):
    """An argument has the wrong shape, type, range, or is not finite."""


class InvalidSamples(InvalidInput):
    """A samples table (CSV or arrays) cannot be used.

    Attributes:
        source: File name or description of where the samples came from.
        line: 1-based line number in the file when known, else None.
    """

    def __init__(self, message: str, source: str | None = None, line: int | None = None):
        where = ""
        if source is not None:
            where = f"{source}"
            if line is not None:
                where += f", line {line}"
            where += ": "
        super().__init__(where + message)
        self.source = source
        self.line = line


class ConventionMistake(InvalidSamples):
    """The data fit only when read in another convention (radians for degrees, x,y,z,w for w,x,y,z,
    ...).

    Attributes:
        reading: What the data fit under, e.g. ``"Euler angles in radians"``.
        fix: What to change in the input.
    """

    def __init__(self, message: str, source: str | None = None, reading: str = "", fix: str = ""):
        super().__init__(message, source)
        self.reading = reading
        self.fix = fix


class UnexplainedReadings(InvalidSamples):
    """The calibration explains almost none of the variation of the readings across poses: the
    columns hold something other than their names say (forces and torques swapped, channels in
    another order), or the orientations belong to other readings.

    Attributes:
        explained: Share of the variation across poses the fit explains (pooled over the six
            channels in N and N·m; 1: all of it).
        threshold: The least share accepted.
    """

    def __init__(self, message: str, explained: float, threshold: float, source=None):
        super().__init__(message, source)
        self.explained = explained
        self.threshold = threshold


class FrameNotFound(FtkinError, KeyError):
    """A frame name is not in the robot model.

    Attributes:
        name: The name that was asked for.
        available: Names of the frames the model has.
        hint: What to do about it (e.g. how to add a missing sensor frame), or "".
    """

    def __init__(self, name: str, available: Sequence[str], hint: str = ""):
        self.name = name
        self.available = list(available)
        self.hint = hint
        super().__init__(name)

    def __str__(self) -> str:
        import difflib

        close = difflib.get_close_matches(self.name, self.available, n=1, cutoff=0.6)
        lowered = [frame for frame in self.available if frame.lower() == self.name.lower()]
        suggestion = (lowered or close or [None])[0]
        text = f"frame {self.name!r} not found in the model"
        if suggestion is not None:
            text += f"; did you mean {suggestion!r}?"
        elif self.hint:
            text += f"; {self.hint}"
        return text + "; available frames: " + ", ".join(self.available)


class UrdfError(FtkinError):
    """A URDF cannot be loaded; the message gives the real reason.

    Attributes:
        path: Path (or description) of the URDF.
        reasons: Individual problems found (XML errors, invalid fields,
            missing mesh files, Pinocchio's own message).
    """

    def __init__(self, path: str, reasons: Sequence[str]):
        self.path = path
        self.reasons = list(reasons)
        super().__init__(f"cannot load URDF {path}: " + "; ".join(self.reasons))


class UnobservableParameters(FtkinError):
    """The poses cannot determine some calibration parameters.

    Attributes:
        names: Parameters (or parameter groups) that are not determined.
        singular_values: Singular values of the whitened Jacobian (or regressor) with unit-norm
            columns, relative to the largest, largest first, when available.
        combination: The direction the data cannot see, ``((name, coefficient), ...)`` in each
            parameter's own unit, the first coefficient 1: moving the parameters along it leaves
            every prediction as it was (e.g. ``(("gravity_in_base[z]", 1.0),
            ("force_offset[z]", -1.0))``); empty when not computed.
    """

    def __init__(self, names: Sequence[str], reason: str, singular_values=None, combination=()):
        self.names = list(names)
        self.reason = reason
        self.singular_values = singular_values
        self.combination = tuple((str(name), float(value)) for name, value in combination)
        text = "the poses cannot determine " + ", ".join(self.names) + f": {reason}"
        if self.combination:
            along = " ".join(f"{value:+.3g} {name}" for name, value in self.combination)
            text += f" (the readings stay the same along {along})"
        super().__init__(text)


class CalibrationFileError(FtkinError):
    """A calibration file cannot be read: wrong format, version, or content.

    Attributes:
        path: The file.
        key: The offending key when one is to blame, else None.
    """

    def __init__(self, path: str, message: str, key: str | None = None):
        self.path = path
        self.key = key
        where = f"{path}" + (f", key {key!r}" if key is not None else "")
        super().__init__(f"{where}: {message}")


class MissingDependency(FtkinError, ImportError):
    """An optional dependency is not installed; the message says which extra."""

    def __init__(self, package: str, extra: str, purpose: str):
        self.package = package
        self.extra = extra
        super().__init__(
            f"{purpose} needs the optional package {package!r} (the extra ftkin[{extra}]); "
            f"install it with: {install_command(extra)}"
        )


def install_command(extra: str) -> str:
    """The command that installs ftkin's ``extra`` (ftkin is installed from its checkout, not
    from PyPI): ``pip install -e '<the checkout>[extra]'``, a path that works from any folder."""
    checkout = Path(__file__).resolve().parents[1]
    return f"pip install -e '{checkout}[{extra}]'"


class SuspectConvention(FtkinError):
    """The readings fit only with a sign or axis convention other than the one assumed.

    Raised by calibration when the fitted tool weight points more than 90°
    away from the expected gravity direction (a sensor reporting the reaction
    instead of the load, or a robot not standing on the floor), or when the
    data fit far better with one sensor axis reversed (a left-handed sensor).

    Attributes:
        explanations: The likely causes, one sentence each.
        fixes: The options (CLI flags and keywords) that would fix each cause.
        sensor_sign: The sign that fits (``-1`` when a reversed sign is suspected), else None.
        flip_axis: The axis whose reversal fits (``"x"``, ``"y"`` or ``"z"``), else None.
    """

    def __init__(
        self,
        message: str,
        explanations: Sequence[str] = (),
        fixes: Sequence[str] = (),
        sensor_sign: int | None = None,
        flip_axis: str | None = None,
    ):
        self.explanations = list(explanations)
        self.fixes = list(fixes)
        self.sensor_sign = sensor_sign
        self.flip_axis = flip_axis
        super().__init__(message)


class RobotError(FtkinError):
    """The robot refused a command, reported an error, or cannot be reached.

    Attributes:
        host: The robot's address, when known.
        driver_message: The driver's own message (e.g. libfranka's), when there is one.
    """

    def __init__(self, message: str, host: str | None = None, driver_message: str = ""):
        self.host = host
        self.driver_message = driver_message
        super().__init__(message + (f" ({driver_message})" if driver_message else ""))


class RobotConnectionLost(RobotError):
    """The connection to the robot is lost or cannot be opened (network, server stopped)."""


class RealtimeUnavailable(RobotError):
    """The kernel has no real-time scheduling and ``realtime=True`` asked for it."""


class SensorError(FtkinError):
    """The force/torque sensor failed: its read raised, a value is not finite, or it is stale.

    Attributes:
        kind: What failed. The robot stage's checks raise ``"read_failed"``, ``"not_finite"`` and
            ``"stale"``; the adapters of :mod:`ftkin.sensors` raise their own (``"status"``,
            ``"stall"``, ``"silence"``, ``"lag"``, ``"driver"``, ``"units"``, ``"configuration"``,
            ``"connect"``, ``"closed"``: :mod:`ftkin.sensors.stream` says what each means), and
            a control loop stops with it as its reason.
    """

    def __init__(self, kind: str, message: str):
        self.kind = kind
        super().__init__(message)


class NonPhysicalPayload(InvalidInput):
    """A payload difference is not a rigid body (negative mass, inertia not positive definite).

    Attributes:
        setting: The setting to check (e.g. the robot's configured end effector).
    """

    def __init__(self, message: str, setting: str = ""):
        self.setting = setting
        super().__init__(message)


class SessionInterrupted(FtkinError):
    """A calibration session on a robot stopped before its end; the recorded poses are kept.

    Attributes:
        reason: What stopped it (a sensor fault, a robot error, Ctrl-C).
        poses_recorded: Poses in the samples file.
        poses_total: Poses of the session.
        samples_path: The samples file (complete up to the last recorded pose).
    """

    def __init__(self, reason: str, poses_recorded: int, poses_total: int, samples_path):
        self.reason = reason
        self.poses_recorded = poses_recorded
        self.poses_total = poses_total
        self.samples_path = samples_path
        super().__init__(
            f"session stopped after {poses_recorded} of {poses_total} poses: {reason}; the "
            f"samples recorded so far are in {samples_path}: calibrate_on_robot(..., "
            "resume=True) finishes the session"
        )


class RecordingInterrupted(SessionInterrupted):
    """A recording from an arm ftkin does not drive (``ftkin record``) stopped by a fault; the
    recorded poses are kept (whole poses only) and ``resume=True`` (``--resume``) continues it.

    Attributes: those of :class:`SessionInterrupted`.
    """

    def __init__(self, reason: str, poses_recorded: int, poses_total: int, samples_path):
        super().__init__(reason, poses_recorded, poses_total, samples_path)
        self.args = (
            f"recording stopped after {poses_recorded} of {poses_total} poses: {reason}; the "
            f"poses recorded so far are in {samples_path}: record_poses(..., resume=True) "
            "(ftkin record --resume) continues it",
        )


class InconsistentPoses(FtkinError):
    """Poses of a calibration session whose readings do not fit the others, measured again and
    still off (something touched the tool or the arm there): nothing is calibrated, written or
    sent.

    Attributes:
        pose_ids: The poses (indices in the session's plan).
        details: One line per pose: its residuals against a fit of the others, and its score.
        samples_path: The samples file (it holds the poses that fit, not these).
    """

    def __init__(self, pose_ids: Sequence[int], details: Sequence[str], samples_path):
        self.pose_ids = [int(pose) for pose in pose_ids]
        self.details = list(details)
        self.samples_path = samples_path
        super().__init__(
            f"pose(s) {', '.join(map(str, self.pose_ids))} do not fit the other poses, measured "
            f"again and still off ({'; '.join(self.details)}): something touches the tool or "
            "the arm there (a cable, a link of the arm, a hand), or the tool moved on the sensor. "
            f"Nothing was calibrated or written; {samples_path} holds the poses that fit. Remove "
            "the cause and resume the session (resume=True, --resume) to measure them again, or "
            "plan anew with a larger clearance (clearance=, --clearance) in a new samples file"
        )
