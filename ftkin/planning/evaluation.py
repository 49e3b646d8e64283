"""Predicted accuracy of a calibration pose set, before any reading is taken.

:func:`evaluate_poses` gives the standard error of every calibration parameter
that a set of sensor orientations will yield, from the Fisher information the
maximum-likelihood estimator uses (:mod:`ftkin.calibration.information`), for an expected
tool (weight, centre of mass) and sensor noise. The biases cannot do better
than ``σ/√(N r)`` per channel (``N`` poses, ``r`` readings per pose); the
report shows how close a set comes.
"""

from dataclasses import dataclass, field

import numpy as np

from ..calibration.information import (
    SensorNoise,
    covariance_from_information,
    fisher_information,
    standard_errors,
)
from ..calibration.model import STANDARD_GRAVITY, SensorModel
from ..calibration.mount import MOUNT_NAMES, MountMode, split_information
from ..calibration.observability import check_pose_count
from ..calibration.random_walk import walk_gains
from ..exceptions import InvalidInput
from ..validation import (
    as_float_array,
    as_in_range,
    as_rotation_batch,
    as_vector,
    from_fields,
    set_checked,
    whole_number,
)
from .drift_order import DEFAULT_POSE_INTERVAL, check_drift_options, walk_information

PAPER_TOOL_WEIGHT = 3.15
"""The paper's tool weight [N] (gripper plus the sensor's sensitive end)."""

PAPER_CENTER_OF_MASS = (0.0, 0.0, 0.047)
"""The paper's tool centre of mass in the sensor frame [m]."""

_ROWS = (
    (("ax", "ay", "az"), "N"),
    (("fx0", "fy0", "fz0"), "N"),
    (("mx0", "my0", "mz0"), "N·m"),
    (("px", "py", "pz"), "m"),
)
"""Short names and unit of each block of ``θ`` in :meth:`PoseEvaluation.report`."""


def expected_tool(
    tool_weight: float | None = None, center_of_mass=None, g: float = STANDARD_GRAVITY
) -> SensorModel:
    """The tool a plan is made for: weight [N] hanging straight down the base z axis, COM [m, sensor
    frame].
    """
    weight = (
        PAPER_TOOL_WEIGHT
        if tool_weight is None
        else as_in_range(tool_weight, "tool_weight", 1e-6, 1e6, "N")
    )
    com = as_vector(
        PAPER_CENTER_OF_MASS if center_of_mass is None else center_of_mass, 3, "center_of_mass"
    )
    if np.linalg.norm(com) > 10.0:
        raise InvalidInput(
            f"center_of_mass must lie within 10 m of the sensor, got {com.tolist()} m"
        )
    return SensorModel.from_tool(weight / g, com, g=g)


@dataclass(frozen=True)
class PoseEvaluation:
    """Predicted information and standard errors of a pose set.

    Attributes:
        rotations: ``(N, 3, 3)`` sensor orientations ``R_BS``.
        model: Expected tool the prediction is for (biases play no role).
        noise: Per-reading sensor noise.
        readings_per_pose: Readings averaged at each pose.
        information: ``(12, 12)`` Fisher information of ``θ = [a, F0, M0, P]``.
        covariance: Its inverse.
        standard_errors: Per parameter, see :func:`ftkin.calibration.information.standard_errors`.
        mount_mode: ``"none"``, or the mount estimated with the parameters
            (``information`` is then θ's marginal information, mount estimated).
        mount_covariance: ``(k, k)`` covariance of the mount angles [rad²], else None.
        drift_rate: ``(2,)`` random-walk rate of the bias [N/√s, N·m/√s] the
            prediction integrates out (poses visited in the given order, one
            every ``pose_interval`` s), else None (a constant bias).
        pose_interval: Time from one pose to the next [s] (with ``drift_rate``;
            the median one when ``pose_times`` are given).
        pose_times: ``(N,)`` the poses' times [s] when given, else None.
    """

    rotations: np.ndarray
    model: SensorModel
    noise: SensorNoise
    readings_per_pose: int
    information: np.ndarray
    covariance: np.ndarray
    standard_errors: dict
    mount_mode: str = "none"
    mount_covariance: np.ndarray | None = None
    drift_rate: np.ndarray | None = None
    pose_interval: float | None = None
    pose_times: np.ndarray | None = None

    @property
    def mount_std_deg(self) -> dict[str, float]:
        """Predicted standard errors [deg] of the mount angles by name (empty without a mount)."""
        if self.mount_covariance is None:
            return {}
        sigma = np.rad2deg(np.sqrt(np.diag(self.mount_covariance)))  # [deg]
        return dict(zip(MOUNT_NAMES[self.mount_mode], sigma.tolist()))

    @property
    def pose_count(self) -> int:
        """Number of poses."""
        return len(self.rotations)

    @property
    def vector_std(self) -> np.ndarray:
        """``(12,)`` standard errors of ``θ = [a, F0, M0, P]`` [N, N, N·m, m]."""
        return np.sqrt(np.diag(self.covariance))

    @property
    def bias_bound(self) -> np.ndarray:
        """``(6,)`` lowest possible bias standard errors ``σ/√(N r)`` [N, N·m]."""
        return self.noise.channel_std / np.sqrt(self.pose_count * self.readings_per_pose)

    def report(self) -> str:
        """Table of predicted standard errors (and, for biases, the ratio to the bound)."""
        std, bound = self.vector_std.reshape(4, 3), self.bias_bound.reshape(2, 3)
        lines = [
            f"predicted standard errors for {self.pose_count} poses × {self.readings_per_pose} "
            "reading(s), "
            f"tool {self.model.tool_weight:.3g} N with COM "
            f"{np.round(self.model.center_of_mass, 4).tolist()} m, "
            f"noise {self.noise.force_std[0]:g} N / {self.noise.torque_std[0]:g} N·m",
            *(
                []
                if self.drift_rate is None
                else [
                    f"bias drifting as a random walk of {self.drift_rate[0]:g} N/√s, "
                    f"{self.drift_rate[1]:g} N·m/√s, "
                    + (
                        f"poses visited in this order one every {self.pose_interval:g} s"
                        if self.pose_times is None
                        else f"poses at their times ({self.pose_times[0]:g} to "
                        f"{self.pose_times[-1]:g} s)"
                    )
                ]
            ),
            f"{'parameter':<10}{'std error':>14}  {'unit':<5}{'bound σ/√N':>14}{'ratio':>8}",
        ]
        for block, (names, unit) in enumerate(_ROWS):
            for axis, name in enumerate(names):
                row = f"{name:<10}{std[block, axis]:>14.3e}  {unit:<5}"
                if block in (1, 2):
                    limit = bound[block - 1, axis]
                    row += f"{limit:>14.3e}{std[block, axis] / limit:>8.3f}"
                lines.append(row)
        tilt_deg = np.rad2deg(self.standard_errors["base_tilt"])
        lines += [
            f"{'weight G':<10}{self.standard_errors['tool_weight']:>14.3e}  N",
            f"{'tilt U, V':<10}{tilt_deg[0]:>14.3e}, {tilt_deg[1]:.3e} deg",
            *(f"{name:<10}{value:>14.3e}  deg" for name, value in self.mount_std_deg.items()),
        ]
        return "\n".join(lines)


def _pose_times(value, count: int) -> np.ndarray:
    times = as_float_array(value, "pose_times")
    if times.shape != (count,) or not np.all(np.isfinite(times)) or np.any(np.diff(times) <= 0):
        raise InvalidInput(
            f"pose_times must be {count} finite, strictly increasing times [s] (one per pose, in "
            f"visiting order), got shape {times.shape}"
        )
    return times


@dataclass(frozen=True, eq=False)
class ExpectedCalibration:
    """The calibration a pose set is planned or evaluated for: tool, noise and estimation.

    Attributes:
        tool_weight: Expected tool weight [N] (None: 3.15 N, the paper's).
        center_of_mass: Expected COM in the sensor frame [m] (None: 47 mm along z).
        noise: Per-reading noise (None: :meth:`SensorNoise.paper`: 0.02 N, 0.002 N·m).
        readings_per_pose: Independent readings averaged at each pose.
        estimate_mount: ``"yaw"`` or ``"full"``: the calibration will also
            estimate the sensor's mount (:mod:`ftkin.calibration.mount`; the
            rotations are the URDF's, the mount assumed near identity).
        drift_rate: ``[force N/√s, torque N·m/√s]``: the bias drifts as a
            random walk of this rate, and the prediction is for a
            ``random-walk`` calibration (the walk integrated out,
            :mod:`ftkin.planning.drift_order`; stored per channel, ``(6,)``).
            Not with ``estimate_mount``.
        pose_interval: Time from one pose to the next [s] (with ``drift_rate``; None:
            :data:`~ftkin.planning.drift_order.DEFAULT_POSE_INTERVAL`). Refused without
            ``drift_rate`` (the time between poses matters only to a drift); None then.
        model: The expected tool as a :class:`SensorModel` (derived; biases play no role).
    """

    tool_weight: float | None = None
    center_of_mass: object = None
    noise: SensorNoise | None = None
    readings_per_pose: int = 1
    estimate_mount: MountMode | str = MountMode.NONE
    drift_rate: object = None
    pose_interval: float | None = None
    model: SensorModel = field(init=False, repr=False)

    def __post_init__(self):
        if self.noise is not None and not isinstance(self.noise, SensorNoise):
            raise InvalidInput(
                f"noise must be an ftkin.SensorNoise, got {type(self.noise).__name__}"
            )
        object.__setattr__(self, "estimate_mount", MountMode.of(self.estimate_mount))
        if self.drift_rate is None and self.pose_interval is not None:
            raise InvalidInput(
                f"pose_interval ({self.pose_interval!r} s) applies with drift_rate (the time "
                "between poses matters only to a drift): give drift_rate, or no pose_interval"
            )
        drift_rate, interval = check_drift_options(
            self.drift_rate,
            DEFAULT_POSE_INTERVAL if self.pose_interval is None else self.pose_interval,
            self.estimate_mount,
        )
        set_checked(
            self,
            model=expected_tool(self.tool_weight, self.center_of_mass),
            noise=self.noise if self.noise is not None else SensorNoise.paper(),
            readings_per_pose=whole_number(self.readings_per_pose, "readings_per_pose", 1),
            drift_rate=drift_rate,
            pose_interval=None if drift_rate is None else interval,
        )


def evaluate_poses(
    rotation_sensor_to_base,
    expected: ExpectedCalibration | None = None,
    *,
    pose_times=None,
    **options,
) -> PoseEvaluation:
    """Predict the calibration's standard errors for sensor orientations ``(N, 3, 3)``.

    Args:
        rotation_sensor_to_base: ``R_BS`` of each pose (in visiting order, for a drift).
        expected: The calibration to predict for; or give its fields as keywords
            (``evaluate_poses(rotations, tool_weight=15.0, noise=...)``).
        pose_times: ``(N,)`` time of each pose [s] (with a drift rate; instead of one
            every ``pose_interval``), strictly increasing.

    Raises:
        UnobservableParameters: fewer than three poses, or orientations that
            leave parameters undetermined (named).
        InvalidInput: not rotation matrices, or a bad tool, noise or reading count.
    """
    if expected is None:
        expected = from_fields(ExpectedCalibration, options, "evaluate_poses")
    elif options:
        raise InvalidInput("give an ExpectedCalibration or its fields as keywords, not both")
    rotations, _ = as_rotation_batch(rotation_sensor_to_base)
    check_pose_count(len(rotations))
    model, noise, readings = expected.model, expected.noise, expected.readings_per_pose
    drift_rate, times, mount_covariance = expected.drift_rate, None, None
    if drift_rate is not None:
        times = (
            np.arange(len(rotations)) * expected.pose_interval
            if pose_times is None
            else _pose_times(pose_times, len(rotations))
        )
        variance = np.tile(noise.channel_std**2 / readings, (len(rotations), 1))
        information = walk_information(
            model.parameter_jacobian(rotations), walk_gains(times, variance, drift_rate)
        )
    else:
        information = fisher_information(model, rotations, noise, readings, expected.estimate_mount)
    if expected.estimate_mount != "none":
        information, mount_covariance = split_information(information)
    covariance = covariance_from_information(information)
    timed = drift_rate is not None and pose_times is not None
    return PoseEvaluation(
        rotations=rotations,
        model=model,
        noise=noise,
        readings_per_pose=readings,
        information=information,
        covariance=covariance,
        standard_errors=standard_errors(model, covariance),
        mount_mode=expected.estimate_mount,
        mount_covariance=mount_covariance,
        drift_rate=None if drift_rate is None else drift_rate[[0, 3]],
        pose_interval=None
        if drift_rate is None
        else (float(np.median(np.diff(times))) if timed else expected.pose_interval),
        pose_times=times if timed else None,
    )
