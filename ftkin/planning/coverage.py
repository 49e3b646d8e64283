"""What the poses recorded so far leave undetermined, and the orientation that would help most.

A recorder that waits for an arm moved by hand or by its own program (``ftkin record``,
:mod:`ftkin.robot.recorder`) asks after each pose: how well would a calibration from these poses
determine each parameter, which combination of parameters is the weakest, and where should
gravity point in the sensor frame at the next pose? :func:`assess_coverage` answers from the
Fisher information of :mod:`ftkin.calibration.information`, the one the planner and the
maximum-likelihood fit use, evaluated for the tool the readings suggest:

* each parameter's predicted standard error (:func:`~ftkin.planning.evaluation.evaluate_poses`)
  and its **ratio to the ideal**: what ``N`` well-spread poses of ``r`` readings could give at
  best, ``σ/√(N r)`` per channel (the bias bound of :mod:`ftkin.planning.evaluation`); for the
  gravity vector ``a`` the force bound, for the centre of mass the torque bound over the tool
  weight ``G``;
* the **weakest direction**: the eigenvector of the information, in those ideal units, with the
  smallest eigenvalue, named by the parameters it involves (the largest components); while the
  poses leave parameters undetermined, every parameter in the null space (it may have several
  directions: three poses that differ by a turn about the vertical leave four);
* the **next pose**: among :data:`CANDIDATES` gravity directions spread over the sphere, each
  reached from the last pose by the smallest turn of the tool, the one that adds the most
  information (D-optimal, ``log det``, as :mod:`ftkin.planning.design` chooses a plan), and what
  the weakest parameter's standard error would then be.

Which directions an arm can reach is not known here (no arm model is needed): the advice names
a gravity direction in the sensor frame (``"its +x axis down"``), and the user finds the pose.
"""

from dataclasses import dataclass

import numpy as np

from ..calibration.information import SensorNoise, fisher_information
from ..calibration.model import COMPONENT_NAMES, SensorModel
from ..exceptions import InvalidInput, UnobservableParameters
from ..validation import as_rotation_batch, whole_number
from .design import REGULARIZATION, information_factors, log_det
from .evaluation import ExpectedCalibration, PoseEvaluation, evaluate_poses

CANDIDATES = 256
"""Gravity directions tried for the next pose (a Fibonacci sphere: about 13° apart)."""

NULL_EIGENVALUE = 1e-9
"""An eigenvalue of the information (in ideal units) below this, relative to the largest, is a
direction the poses leave undetermined."""

DOWN = np.array([0.0, 0.0, -1.0])
"""Gravity's direction in the base frame."""

_UNITS = ("N",) * 6 + ("N·m",) * 3 + ("mm",) * 3
_SCALE_TO_UNIT = np.array([1.0] * 9 + [1e3] * 3)  # the centre of mass is shown in mm


def fibonacci_sphere(count: int) -> np.ndarray:
    """``(count, 3)`` unit vectors spread evenly over the sphere (deterministic)."""
    k = np.arange(count) + 0.5
    z = 1.0 - 2.0 * k / count
    angle = np.pi * (1.0 + np.sqrt(5.0)) * k
    radius = np.sqrt(1.0 - z * z)
    return np.stack([radius * np.cos(angle), radius * np.sin(angle), z], axis=1)


def turn_between(start, end) -> np.ndarray:
    """The rotation ``(3, 3)`` by the smallest angle that takes unit vector ``start`` to ``end``
    (about ``start × end``; half a turn about a perpendicular axis when they are opposite)."""
    start, end = np.asarray(start, float), np.asarray(end, float)
    axis = np.cross(start, end)
    sine, cosine = np.linalg.norm(axis), float(np.dot(start, end))
    if sine < 1e-12:
        if cosine > 0.0:
            return np.eye(3)
        helper = np.eye(3)[int(np.argmin(np.abs(start)))]
        axis = np.cross(start, helper)
        axis /= np.linalg.norm(axis)
        return 2.0 * np.outer(axis, axis) - np.eye(3)  # half a turn about ``axis``
    k = axis / sine
    cross = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + sine * cross + (1.0 - cosine) * cross @ cross


def rotations_from_gravity(directions) -> np.ndarray:
    """Sensor orientations ``R_BS`` ``(N, 3, 3)`` that see gravity along ``directions`` ``(N, 3)``
    (unit vectors in the sensor frame): ``R_BSᵀ [0, 0, −1] = d``, the turn about the base's
    vertical chosen as the smallest turn from the upright sensor. For readings without an
    orientation (the IMU's specific force gives ``d = −a/|a|``): the wrench model depends on the
    orientation through gravity's direction alone, up to the base tilt.
    """
    directions = np.asarray(directions, dtype=float).reshape(-1, 3)
    return np.array([turn_between(DOWN, d).T for d in directions])


@dataclass(frozen=True)
class PoseCoverage:
    """How well the poses so far determine the calibration, and the next pose that helps most.

    Attributes:
        gravity_directions: ``(N, 3)`` gravity's unit direction at each pose, sensor frame.
        evaluation: The predicted standard errors, or None while the poses leave parameters
            undetermined (fewer than three, or alike).
        ratios: ``(12,)`` standard error of each entry of ``θ = [a, F0, M0, P]`` over the ideal
            ``σ/√(N r)`` (module docstring), or None with ``evaluation``.
        weakest: Names of the entries of ``θ`` in the weakest direction
            (:data:`~ftkin.calibration.model.COMPONENT_NAMES`).
        next_gravity: ``(3,)`` gravity's direction in the sensor frame at the suggested pose.
        next_angle: Its angle from the nearest pose so far [rad].
        next_std: ``(12,)`` standard errors of ``θ`` predicted after adding that pose [N, N,
            N·m, m] (None while it would still leave parameters undetermined).
        frame: The frame the directions are in, for messages (``"sensor"``, ``"IMU"``).
    """

    gravity_directions: np.ndarray
    evaluation: PoseEvaluation | None
    ratios: np.ndarray | None
    weakest: tuple[str, ...]
    next_gravity: np.ndarray
    next_angle: float
    next_std: np.ndarray | None
    frame: str = "sensor"

    @property
    def pose_count(self) -> int:
        """Poses assessed."""
        return len(self.gravity_directions)

    @property
    def determined(self) -> bool:
        """True when a calibration from these poses determines every parameter."""
        return self.evaluation is not None

    @property
    def worst(self) -> tuple[str, float, float, str] | None:
        """``(name, standard error, ratio to the ideal, unit)`` of the least determined entry of
        ``θ`` (the centre of mass in mm), or None while undetermined."""
        if self.ratios is None:
            return None
        i = int(np.argmax(self.ratios))
        std = float(self.evaluation.vector_std[i] * _SCALE_TO_UNIT[i])
        return COMPONENT_NAMES[i], std, float(self.ratios[i]), _UNITS[i]

    def describe(self) -> str:
        """One line: the weakest parameter (or what is still open) and the next pose."""
        axis = int(np.argmax(np.abs(self.next_gravity)))
        sign = "+" if self.next_gravity[axis] > 0 else "-"
        vector = ", ".join(f"{value:+.2f}" for value in self.next_gravity)
        advice = (
            f"next: gravity along [{vector}] in the {self.frame} frame (its {sign}{'xyz'[axis]} "
            f"axis down), {np.rad2deg(self.next_angle):.0f}° from the nearest pose so far"
        )
        if self.worst is None:
            then = "" if self.next_std is None else ": that pose would determine them"
            return (
                f"{self.pose_count} pose(s) leave {', '.join(self.weakest)} undetermined; "
                + advice
                + then
            )
        name, std, ratio, unit = self.worst
        i = COMPONENT_NAMES.index(name)
        after = f"; it would bring {name} to ±{self.next_std[i] * _SCALE_TO_UNIT[i]:.3g} {unit}"
        return (
            f"weakest: {name} ±{std:.3g} {unit} ({ratio:.1f}× what ideally spread poses give; "
            f"the weakest direction involves {', '.join(self.weakest)}); {advice}{after}"
        )


def _ideal_scale(model: SensorModel, noise: SensorNoise, readings: int) -> np.ndarray:
    """``(12,)`` one pose's ideal standard error per entry of ``θ`` (module docstring)."""
    force, torque = noise.force_std, noise.torque_std
    weight = max(model.tool_weight, 1e-9)
    return np.concatenate([force, force, torque, torque / weight]) / np.sqrt(readings)


def assess_coverage(
    rotation_sensor_to_base,
    expected: ExpectedCalibration,
    *,
    frame: str = "sensor",
    candidates: int = CANDIDATES,
) -> PoseCoverage:
    """Assess the poses so far (see the module docstring).

    Args:
        rotation_sensor_to_base: ``(N, 3, 3)`` orientations ``R_BS`` of the poses so far, in the
            order recorded (the next pose turns from the last); :func:`rotations_from_gravity`
            for readings without an orientation.
        expected: The tool and noise to predict for (e.g. from a linear fit of the readings so
            far), and the readings per pose.
        frame: The frame the gravity directions are named in.
        candidates: Gravity directions tried for the next pose.

    Raises:
        InvalidInput: no pose, not rotations, or a bad count.
    """
    rotations, _ = as_rotation_batch(rotation_sensor_to_base)
    candidates = whole_number(candidates, "candidates", 1)
    if not len(rotations):
        raise InvalidInput("assess_coverage needs at least one pose")
    model, noise, readings = expected.model, expected.noise, expected.readings_per_pose
    directions = np.einsum("nji,j->ni", rotations, DOWN)
    scale = _ideal_scale(model, noise, readings)
    information = fisher_information(model, rotations, noise, readings) * np.outer(scale, scale)
    ridge = REGULARIZATION * np.eye(12)
    try:
        evaluation = evaluate_poses(rotations, expected)
    except UnobservableParameters:
        evaluation = None
    values, vectors = np.linalg.eigh(information)
    null = values < NULL_EIGENVALUE * max(values[-1], np.finfo(float).tiny)
    # undetermined: every entry in the null space (it may have several directions); else the
    # weakest direction's largest entries
    weight = np.linalg.norm(vectors[:, null], axis=1) if null.any() else np.abs(vectors[:, 0])
    names = tuple(COMPONENT_NAMES[i] for i in np.flatnonzero(weight > 0.3 * weight.max()))
    pool = fibonacci_sphere(candidates)
    last, last_direction = rotations[-1], directions[-1]
    tried = np.array([last @ turn_between(d, last_direction) for d in pool])
    factors = (
        information_factors(
            tried, model.gravity_in_base, model.center_of_mass, noise.channel_std, readings
        )
        * scale[None, None, :]
    )
    added = information + np.transpose(factors, (0, 2, 1)) @ factors
    best = int(np.argmax(log_det(added + ridge)))
    next_gravity = pool[best]
    next_angle = float(np.min(np.arccos(np.clip(directions @ next_gravity, -1.0, 1.0))))
    count = len(rotations)
    ratios = next_std = None
    if evaluation is not None:
        ratios = np.sqrt(count * np.diag(np.linalg.inv(information)))
    after = np.linalg.eigvalsh(added[best])
    if after[0] > NULL_EIGENVALUE * after[-1]:
        next_std = scale * np.sqrt(np.diag(np.linalg.inv(added[best])))
    return PoseCoverage(
        directions, evaluation, ratios, names, next_gravity, next_angle, next_std, frame
    )
