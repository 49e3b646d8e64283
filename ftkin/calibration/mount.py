"""The sensor's real rotation on the flange: the mount ``R_M`` in the ML fit.

A URDF rarely knows how the sensor is clocked on its adapter plate. With
``R_M`` the rotation taking coordinates in the URDF's sensor frame to the real
sensor frame, the real orientation is ``R_BS = R_BS_urdf · R_Mᵀ`` and the model
of :mod:`ftkin.calibration.model` reads, per pose ``i`` with ``u_i = R_iᵀ a``
(gravity in the URDF sensor frame),

    Gs_i = R_M u_i,    F_i = F0 + Gs_i,    M_i = M0 + P × Gs_i.

``R_M`` lives on SO(3) (det = +1 always): ``R_M = R_M0 · Exp(E δ)`` with
``R_M0`` the current estimate and ``δ`` a local increment, ``E = e_z`` for
``"yaw"`` (one angle about the sensor z axis) or ``E = I`` for ``"full"`` (a
rotation vector, axes of the real sensor frame). Derivatives use the right
Jacobian of the exponential map, ``∂(Exp(w) u)/∂w = −Exp(w) [u]× J_r(w)``.

Observability: a change ``δ`` of the mount can be traded for a change of the
gravity direction ``a`` and bias ``F0`` when the part of ``R_i δ`` (the mount
axis in base coordinates) perpendicular to gravity is the same at every pose.
For ``"yaw"`` that happens when gravity lies along the sensor z axis at every
pose (tool straight down or up): turning the sensor about z then changes no
reading. :func:`check_mount_observable` refuses such pose sets by name.
"""

from dataclasses import replace
from enum import StrEnum

import numpy as np
import pinocchio as pin

from ..exceptions import InvalidInput, UnobservableParameters
from .covariance import invert_information, weakest_directions
from .linear import fit_linear
from .model import COMPONENT_NAMES, gravity_in_sensor, parameter_jacobian, skew
from .observability import MIN_RELATIVE_SINGULAR_VALUE, force_regressor
from .samples import PoseAverages

MOUNT_MODES = ("none", "yaw", "full")
"""Values of ``estimate_mount``: no mount, a rotation about the sensor z axis, any rotation."""

MOUNT_NAMES = {"none": (), "yaw": ("mount[z]",), "full": ("mount[x]", "mount[y]", "mount[z]")}
"""Names of the mount increments ``δ`` [rad] per mode (rotation about the real sensor's axes)."""

YAW_START_GRID = np.deg2rad(np.arange(0.0, 360.0, 15.0))
"""Yaw angles [rad] tried for the starting point (the linear fit's force residual picks one)."""

MOUNT_AXES = {"none": np.zeros((3, 0)), "yaw": np.array([[0.0], [0.0], [1.0]]), "full": np.eye(3)}
"""Axes ``E`` of the mount increment per mode: ``R_M = R_M0 · Exp(E δ)``."""

POSES_NEEDED = {
    "yaw": (
        "turning the sensor about its z axis changes no reading while gravity lies along that "
        "axis: use poses "
        "with the tool tilted 30° or more from vertical, about at least two different horizontal "
        "axes"
    ),
    "full": (
        "use poses that turn gravity into every sensor direction: the tool tilted 30° or more "
        "about at least "
        "two different horizontal axes, and the wrist turned so gravity is seen along the sensor's "
        "x, y and z axes"
    ),
}
"""What pose sets each mode needs (said when a mount is refused as unobservable)."""


class MountMode(StrEnum):
    """What the fit estimates of the sensor's mount on the flange (``estimate_mount``).

    A :class:`~enum.StrEnum`: it compares equal to its text (``MountMode.YAW == "yaw"``). The
    text is checked once, where it enters (:meth:`of`, called by
    :class:`~ftkin.calibration.fit_options.CalibrationOptions`, the result's and the planner's
    types and the public entry points); the functions behind them trust a ``MountMode``.
    """

    NONE = "none"
    YAW = "yaw"
    FULL = "full"

    @classmethod
    def of(cls, value) -> "MountMode":
        """``value`` as a mode (a mode passes as it is), else :class:`InvalidInput`."""
        if isinstance(value, cls):
            return value
        try:
            return cls(value)
        except ValueError:
            raise InvalidInput(
                f"unknown estimate_mount {value!r}; expected one of {', '.join(MOUNT_MODES)}"
            ) from None


def check_mount_mode(estimate_mount) -> MountMode:
    """:meth:`MountMode.of` (the name kept for the callers of the release before)."""
    return MountMode.of(estimate_mount)


def exp_so3(rotation_vector) -> np.ndarray:
    """``Exp(w)``: rotation matrix of a rotation vector ``w`` [rad] (Pinocchio's ``exp3``)."""
    return pin.exp3(np.asarray(rotation_vector, dtype=float))


def right_jacobian_so3(rotation_vector) -> np.ndarray:
    """Right Jacobian ``J_r(w)`` of SO(3): ``Exp(w + dw) ≈ Exp(w) Exp(J_r(w) dw)`` (Pinocchio's
    ``Jexp3``).
    """
    return pin.Jexp3(np.asarray(rotation_vector, dtype=float))


def mount_rotation(base: np.ndarray, mode: str, increment) -> np.ndarray:
    """``R_M = base · Exp(E δ)`` for the mode's axes ``E``."""
    return base @ exp_so3(MOUNT_AXES[mode] @ np.asarray(increment, dtype=float))


def force_step_cost(
    rotations: np.ndarray, forces: np.ndarray, mode: str = "none"
) -> tuple[float, np.ndarray]:
    """Smallest force residual sum of squares [N²] of the paper's force step, and the mount it took.

    ``mode="none"``: the mount is the identity; otherwise the best yaw of
    :data:`YAW_START_GRID` (a fixed mount keeps the force step linear, with
    rotations ``R_i R_Mᵀ``).
    """
    costs, mounts = force_step_costs(rotations, np.asarray(forces)[None], mode)
    return float(costs[0]), mounts[0]


def force_step_costs(
    rotations: np.ndarray, force_sets: np.ndarray, mode: str = "none"
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`force_step_cost` of several force sets ``(k, N, 3)`` [N] at the same ``rotations``
    (one regressor and one factorization per yaw for all of them): costs ``(k,)`` [N²] and
    mounts ``(k, 3, 3)``."""
    force_sets = np.asarray(force_sets, dtype=float)
    values = force_sets.reshape(len(force_sets), -1).T  # (3N, k): one column per set
    best_costs = np.full(len(force_sets), np.inf)
    best_rotations = np.tile(np.eye(3), (len(force_sets), 1, 1))
    grid = YAW_START_GRID if mode != "none" else np.zeros(1)
    for yaw in grid:
        rotation = np.eye(3) if mode == "none" else mount_rotation(np.eye(3), "yaw", [yaw])
        regressor = force_regressor(rotations @ rotation.T)
        fitted = regressor @ np.linalg.lstsq(regressor, values, rcond=None)[0]
        costs = np.sum((values - fitted) ** 2, axis=0)
        better = costs < best_costs
        best_costs[better], best_rotations[better] = costs[better], rotation
    return best_costs, best_rotations


def mount_start(poses: PoseAverages, g: float):
    """Starting mount ``R_M0`` (a yaw from :data:`YAW_START_GRID`) and the two-step linear fit
    there.

    The yaw is the one of :func:`force_step_cost`; the full two-step fit (with
    its observability checks) then runs at that yaw.
    """
    _, rotation = force_step_cost(poses.rotations, poses.wrenches[:, :3], "yaw")
    return rotation, fit_linear(replace(poses, rotations=poses.rotations @ rotation.T), g)


def check_mount_observable(problem, x: np.ndarray) -> None:
    """Refuse pose sets that cannot determine the mount (see the module docstring).

    ``problem`` is the ML fit's :class:`~ftkin.calibration.ml.WeightedProblem` with a mount mode,
    ``x = [θ, δ]`` its parameters.

    The whitened Jacobian with unit-norm columns must have a smallest singular
    value of at least :data:`~ftkin.calibration.observability.MIN_RELATIVE_SINGULAR_VALUE`
    relative to its largest; the error names the mount angles (and any other
    parameter) in the weakest direction and says which poses are needed.
    """
    names = COMPONENT_NAMES + MOUNT_NAMES[problem.mode]
    directions = weakest_directions(
        problem.whitened_jacobian(x), names, MIN_RELATIVE_SINGULAR_VALUE
    )
    relative = directions.relative
    if relative >= MIN_RELATIVE_SINGULAR_VALUE:
        return
    involved = directions.names
    mount_involved = [name for name in involved if name.startswith("mount")] or list(
        MOUNT_NAMES[problem.mode]
    )
    others = [name for name in involved if not name.startswith("mount")]
    raise directions.error(
        f"{POSES_NEEDED[problem.mode]} (smallest relative singular value {relative:.1e}, need "
        "at least "
        f"{MIN_RELATIVE_SINGULAR_VALUE:.0e}"
        + (f"; traded against {', '.join(others)}" if others else "")
        + ")",
        mount_involved,
    )


def mount_jacobian(
    rotations: np.ndarray, gravity_in_base, center_of_mass, mode: str, mount=None, increment=None
) -> np.ndarray:
    """``(N, 6, 12 + k)`` derivative of the prediction with respect to ``[θ, δ]``.

    ``rotations`` are the URDF's ``R_BS``; ``mount`` is ``R_M`` at ``δ = increment`` (default
    the identity at ``δ = 0``, what a plan assumes before the mount is known). The ``θ`` columns
    are :func:`~ftkin.calibration.model.parameter_jacobian` at the real orientations; the mount
    columns are ``∂Gs/∂δ = −R_M [u]× J_r(E δ) E`` (``u = R_BS_urdfᵀ a``) and ``[P]× ∂Gs/∂δ``.
    ``mode="none"`` gives the ``(N, 6, 12)`` Jacobian of θ alone.
    """
    mount = np.eye(3) if mount is None else np.asarray(mount, dtype=float)
    gravity, com = np.asarray(gravity_in_base, dtype=float), np.asarray(center_of_mass, dtype=float)
    jac = parameter_jacobian(rotations @ mount.T, gravity, com)
    axes = MOUNT_AXES[mode]  # a MountMode (checked where it entered)
    if mode == "none":
        return jac
    if increment is not None:
        axes = right_jacobian_so3(axes @ np.asarray(increment, dtype=float)) @ axes
    d_gravity = -mount @ skew(gravity_in_sensor(rotations, gravity)) @ axes
    return np.concatenate([jac, np.concatenate([d_gravity, skew(com) @ d_gravity], axis=1)], axis=2)


def split_information(information: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Split a ``(12 + k)`` information matrix into θ's marginal information and the mount
    covariance.

    Returns the Schur complement ``I_θθ − I_θm I_mm⁻¹ I_mθ`` (12, 12), whose
    inverse is θ's covariance with the mount estimated, and the ``(k, k)``
    covariance of the mount increments [rad²] (the mount block of the inverse).

    Raises:
        UnobservableParameters: the information matrix is singular
            (:func:`~ftkin.calibration.covariance.invert_information`), naming the weak
            parameters (and the poses a mount needs).
    """
    mode = "yaw" if information.shape[0] == 13 else "full"
    try:
        covariance = invert_information(
            information,
            COMPONENT_NAMES + MOUNT_NAMES[mode],
            "the information matrix is singular along a combination of them",
        )
    except UnobservableParameters as error:
        if not any(name.startswith("mount") for name in error.names):
            raise
        raise UnobservableParameters(
            error.names, POSES_NEEDED[mode], error.singular_values, error.combination
        ) from None
    theta, mount, cross = information[:12, :12], information[12:, 12:], information[:12, 12:]
    marginal = theta - cross @ np.linalg.solve(mount, cross.T)
    mount_covariance = covariance[12:, 12:]
    return 0.5 * (marginal + marginal.T), 0.5 * (mount_covariance + mount_covariance.T)


def rotation_to_rpy(rotation) -> np.ndarray:
    """URDF roll-pitch-yaw [rad] of a rotation ``R = Rz(yaw) Ry(pitch) Rx(roll)``."""
    r = np.asarray(rotation, dtype=float)
    pitch = np.arctan2(-r[2, 0], np.hypot(r[0, 0], r[1, 0]))
    return np.array([np.arctan2(r[2, 1], r[2, 2]), pitch, np.arctan2(r[1, 0], r[0, 0])])
