"""Fisher information, covariance and standard errors of the calibration parameters.

The same information matrix serves the maximum-likelihood estimator (its
covariance), the pose planner (predicted standard errors of a pose set) and the
Cramér–Rao bound in the benchmarks. Parameters are ``θ = [a, F0, M0, P]``
(see :mod:`ftkin.calibration.model`); derived quantities (tool weight ``G``, mass, base
tilt ``U``, ``V``) get their variance by the delta method.
"""

from dataclasses import dataclass

import numpy as np

from ..exceptions import InvalidInput
from ..validation import as_float_array, as_rotation_batch, check_finite
from .covariance import invert_information
from .model import COMPONENT_NAMES, SensorModel
from .mount import mount_jacobian

NOISE_RANGE = (1e-15, 1e6)
"""Accepted noise standard deviations per reading [N, N·m]: beyond them 1/σ² leaves the float
range's useful part.
"""

NOISE_FLOOR_RELATIVE = 1e-7
"""Smallest noise an estimate from the data may give, relative to the largest reading of its group
(at least 1 N or 1 N·m).

Readings that fit the model to rounding (noise-free simulated data, e.g. a
MuJoCo recording without sensor noise) would otherwise give a noise of
~1e-16, a likelihood without bound and rounding errors flagged as outliers.
A real sensor's noise is orders of magnitude above it (the best resolve ~1e-5 of their range);
the solver's own convergence leaves residuals of ~1e-9 on exact data."""


def noise_floor(wrenches) -> np.ndarray:
    """``(6,)`` floor [N, N·m] of an estimated per-reading noise for readings ``(P, 6)``, forces and
    torques pooled.
    """
    magnitude = np.abs(np.asarray(wrenches, dtype=float))
    groups = [np.max(magnitude[:, part], initial=1.0) for part in (slice(0, 3), slice(3, 6))]
    return NOISE_FLOOR_RELATIVE * np.repeat(groups, 3)


def at_noise_floor(channel_std, wrenches) -> bool:
    """True when an estimated noise ``(6,)`` sits at :func:`noise_floor` (the readings fit the model
    to rounding).
    """
    return bool(
        np.any(np.asarray(channel_std, dtype=float) <= noise_floor(wrenches) * (1.0 + 1e-6))
    )


@dataclass(frozen=True)
class SensorNoise:
    """Standard deviation of one raw sensor reading, per channel.

    Attributes:
        force_std: ``(3,)`` noise of fx, fy, fz [N].
        torque_std: ``(3,)`` noise of mx, my, mz [N·m].
    """

    force_std: np.ndarray
    torque_std: np.ndarray

    def __post_init__(self):
        for name in ("force_std", "torque_std"):
            value = np.broadcast_to(as_float_array(getattr(self, name), name), (3,)).copy()
            if not np.all(np.isfinite(value)) or np.any(value <= 0):
                raise InvalidInput(f"{name} must be finite and positive, got {value}")
            if np.any(value < NOISE_RANGE[0]) or np.any(value > NOISE_RANGE[1]):
                raise InvalidInput(
                    f"{name} must be between {NOISE_RANGE[0]:g} and {NOISE_RANGE[1]:g} (N or N·m "
                    f"per reading), got {value}"
                )
            value.setflags(write=False)
            object.__setattr__(self, name, value)

    @property
    def channel_std(self) -> np.ndarray:
        """``(6,)`` standard deviations ``[fx, fy, fz, mx, my, mz]``."""
        return np.concatenate([self.force_std, self.torque_std])

    @classmethod
    def paper(cls) -> "SensorNoise":
        """Noise of the paper's Leptrino sensor class: 0.02 N and 0.002 N·m per reading."""
        return cls(0.02, 0.002)


def fisher_information(
    model: SensorModel,
    rotation_sensor_to_base,
    noise: SensorNoise,
    readings_per_pose=1,
    estimate_mount: str = "none",
    mount_rotation=None,
) -> np.ndarray:
    """Fisher information ``Σ_i n_i J_iᵀ W J_i`` of ``θ`` for a pose set, ``(12, 12)``.

    With ``estimate_mount="yaw"`` or ``"full"`` it is the ``(12 + k)``
    information of ``[θ, δ]``, ``δ`` the mount angles of
    :mod:`ftkin.calibration.mount` (``k`` = 1 or 3), the rotations then being the
    URDF's ``R_BS`` and ``mount_rotation`` the mount ``R_M`` (default identity).

    Args:
        model: Parameters at which to evaluate (the truth or an estimate).
        rotation_sensor_to_base: ``(N, 3, 3)`` sensor orientations ``R_BS``.
        noise: Per-reading noise; ``W = diag(1/σ²)``.
        readings_per_pose: Number of independent readings averaged at each
            pose (positive; scalar or ``(N,)``).

    Raises:
        InvalidInput: not a rotation batch, ``noise`` not a :class:`SensorNoise`,
            or readings per pose not positive or of the wrong shape.
    """
    rotations, _ = as_rotation_batch(rotation_sensor_to_base)
    if not isinstance(noise, SensorNoise):
        raise InvalidInput(f"noise must be an ftkin.SensorNoise, got {type(noise).__name__}")
    counts = as_float_array(readings_per_pose, "readings_per_pose")
    if counts.ndim > 1 or counts.size not in (1, len(rotations)):
        raise InvalidInput(
            f"readings_per_pose must be a scalar or have shape ({len(rotations)},), got "
            f"{counts.shape}"
        )
    if not np.all(np.isfinite(counts) & (counts > 0)):
        raise InvalidInput(f"readings_per_pose must be finite and positive, got {counts}")
    jac = mount_jacobian(
        rotations, model.gravity_in_base, model.center_of_mass, estimate_mount, mount_rotation
    )
    weights = np.sqrt(np.broadcast_to(counts, (len(rotations),)))[:, None] / noise.channel_std
    stacked = (jac * weights[:, :, None]).reshape(-1, jac.shape[2])
    return stacked.T @ stacked


def _as_parameter_matrix(value, name: str) -> np.ndarray:
    """A finite ``(12, 12)`` matrix over ``θ`` or :class:`InvalidInput`."""
    matrix = as_float_array(value, name)
    if matrix.shape != (12, 12):
        raise InvalidInput(
            f"{name} must have shape (12, 12) over θ = [a, F0, M0, P], got {matrix.shape}"
        )
    check_finite(matrix, name)
    return matrix


def covariance_from_information(information: np.ndarray) -> np.ndarray:
    """Invert a ``(12, 12)`` information matrix over ``θ``
    (:func:`~ftkin.calibration.covariance.invert_information`); raise
    :class:`~ftkin.exceptions.UnobservableParameters` if singular.
    """
    return invert_information(
        _as_parameter_matrix(information, "information"),
        COMPONENT_NAMES,
        "the information matrix is singular along a combination of them",
    )


def derived_gradients(gravity_in_base) -> dict[str, np.ndarray]:
    """Gradients of the derived quantities with respect to ``θ`` (12,) each.

    Keys: ``tool_weight`` (``G = |a|``), ``base_tilt_u``, ``base_tilt_v``.
    """
    a = np.asarray(gravity_in_base, dtype=float)
    ax, ay, az = a
    weight = np.linalg.norm(a)
    gradients = np.zeros((3, 12))
    gradients[0, :3] = a / weight
    # U = asin(-ay / G)
    ratio = -ay / weight
    d_ratio = ay * a / weight**3 - np.array([0.0, 1.0 / weight, 0.0])
    gradients[1, :3] = d_ratio / np.sqrt(max(1.0 - ratio * ratio, 1e-300))
    # V = atan2(ax, -az)
    gradients[2, :3] = np.array([-az, 0.0, ax]) / (ax * ax + az * az)
    return dict(zip(("tool_weight", "base_tilt_u", "base_tilt_v"), gradients))


EXTENDED_NAMES = COMPONENT_NAMES + ("tool_weight", "base_tilt[u]", "base_tilt[v]")
"""Names of the 15 entries of :func:`extended_parameters`: ``θ``, then ``G``, ``U``, ``V``."""


def extended_parameters(model: SensorModel) -> np.ndarray:
    """``(15,)`` ``θ = [a, F0, M0, P]`` followed by the tool weight ``G`` [N] and base tilt ``U``,
    ``V`` [rad].
    """
    return np.concatenate([model.to_vector(), [model.tool_weight], model.base_tilt])


def extended_standard_errors(model: SensorModel, covariance) -> np.ndarray:
    """``(15,)`` standard errors of :func:`extended_parameters` from the ``(12, 12)`` covariance of
    ``θ``.

    ``G``, ``U`` and ``V`` get theirs by the delta method (:func:`derived_gradients`).

    Raises:
        InvalidInput: ``covariance`` is not a finite ``(12, 12)`` matrix.
    """
    covariance = _as_parameter_matrix(covariance, "covariance")
    jacobian = np.vstack([np.eye(12), *derived_gradients(model.gravity_in_base).values()])
    return np.sqrt(np.clip(np.einsum("ij,jk,ik->i", jacobian, covariance, jacobian), 0.0, None))


def standard_errors(model: SensorModel, covariance) -> dict[str, np.ndarray | float]:
    """Standard errors of every parameter from the ``(12, 12)`` covariance of ``θ``.

    Returns a dict with the keys of the calibration file: ``gravity_in_base``,
    ``force_offset``, ``torque_offset``, ``center_of_mass`` (``(3,)`` each, in
    the parameter's unit), ``tool_weight`` [N], ``tool_mass`` [kg] and
    ``base_tilt`` ``(2,)`` [rad]. The same numbers as
    :func:`extended_standard_errors`, by name.
    """
    sigma = extended_standard_errors(model, covariance)
    return {
        "gravity_in_base": sigma[0:3],
        "force_offset": sigma[3:6],
        "torque_offset": sigma[6:9],
        "center_of_mass": sigma[9:12],
        "tool_weight": float(sigma[12]),
        "tool_mass": float(sigma[12]) / model.g,
        "base_tilt": sigma[13:15],
    }
