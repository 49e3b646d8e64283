"""Static calibration from the sensor's IMU: ``F0``, ``M0``, mass, COM, ``R_SI``, accelerometer
bias and scale, from readings at static poses with no orientation at all.

Per pose ``i`` (readings averaged), with ``u_i`` the unit direction of the specific force in the
IMU frame (two nuisance parameters per pose; :mod:`ftkin.calibration.imu_model`)::

    a_i = (1 + s) ∘ g u_i + b                 the accelerometer: |(a_i − b) ⊘ (1 + s)| = g
    F_i = F0 − m g R_SI u_i
    M_i = M0 − m c × (g R_SI u_i)

Why the sphere: the wrench alone sees ``F0 − m R_SI (a − b)``, in which ``F0`` absorbs
``m R_SI b`` (and ``M0`` absorbs ``m c × R_SI b``). Only the accelerometer's own constraint, a
norm of ``g`` at every static pose, separates the bias from the sensor's offsets; the poses must
turn gravity into every direction of the IMU for it to do so. :func:`check_observable` refuses a
pose set that leaves a direction open, naming the parameters.

The fit (:func:`fit_imu_static`) is the joint maximum likelihood of all nine channels
(accelerometer, force, torque) over ``x = [F0, M0, m, c, δ, b, s, e_1..e_P]`` (``R_SI = R0
Exp(δ)``, ``e_i`` the directions' tangent increments), started from a closed form: a sphere fit of
the accelerometer gives ``b`` (and an isotropic ``s``), the Kabsch
rotation of the centred forces against the corrected directions gives ``R_SI`` and ``m``, and
linear least squares of the torques gives ``M0`` and ``c``. Standard errors come from the
Gauss–Newton covariance, as in the ``ml`` fit.
"""

import logging
from dataclasses import dataclass, field, fields, replace

import numpy as np

from ..exceptions import InvalidInput, SuspectConvention, UnobservableParameters
from ..validation import as_float_array, as_rotation_batch, as_vector
from .imu_model import (
    ACCEL_BIAS_NAMES,
    ACCEL_SCALE_NAMES,
    IMU_ROTATION_NAMES,
    corrected_specific_force,
    point_mass_parameters,
    predict_imu,
)
from .imu_result import ImuCalibrationResult
from .imu_samples import ImuPoseAverages, ImuSamples
from .information import SensorNoise, noise_floor
from .model import skew
from .mount import exp_so3, right_jacobian_so3
from .observability import MIN_RELATIVE_SINGULAR_VALUE

logger = logging.getLogger(__name__)

MIN_IMU_POSES = 4
"""Fewest static poses: the sphere ``|a − b| = g`` needs four directions not in one plane."""

MIN_SCALE_POSES = 8
"""Fewest poses for ``estimate_scale="auto"`` to try the scale (six more parameters)."""

NOISE_PASSES = 3
"""Re-estimations of residual-based noise (each followed by a refit)."""

SCALE_MODES = ("auto", "yes", "no")

WRENCH_NAMES = (
    "force_offset[x]",
    "force_offset[y]",
    "force_offset[z]",
    "torque_offset[x]",
    "torque_offset[y]",
    "torque_offset[z]",
    "tool_mass",
    "center_of_mass[x]",
    "center_of_mass[y]",
    "center_of_mass[z]",
)
"""Names of the wrench model's parameters ``[F0, M0, m, c]``."""

POSES_NEEDED = (
    "the accelerometer must see gravity along every IMU direction for |a − b| = g to fix the "
    "bias (else F0 absorbs m·R_SI·b): add static poses that turn the tool about at least two "
    "different horizontal axes, tilted 45° or more, and upside down if the scale is estimated"
)


@dataclass(frozen=True)
class ImuCalibrationOptions:
    """How :func:`calibrate_imu` fits (also ``ftkin.calibrate(imu_samples, ...)``'s keywords).

    Attributes:
        imu_rotation: ``R_SI`` ``(3, 3)`` when known (a datasheet's); None estimates it.
        estimate_scale: ``"auto"`` (default: the scale where the poses determine it, else 0),
            ``"yes"`` (refused when they do not) or ``"no"``.
        wrench_noise: Noise of one raw wrench reading; None estimates it (spread of repeated
            readings, else the residuals).
        accel_noise: Noise of one accelerometer reading [m/s²] (scalar or ``(3,)``); None
            estimates it likewise.
        imu_position: ``r`` ``(3,)`` [m, sensor frame] of the IMU (a datasheet value), recorded
            for the compensation's lever arm; static poses cannot estimate it.
    """

    imu_rotation: object = None
    estimate_scale: str = "auto"
    wrench_noise: SensorNoise | None = None
    accel_noise: object = None
    imu_position: object = None

    def __post_init__(self):
        if self.imu_rotation is not None:
            rotation, single = as_rotation_batch(self.imu_rotation, "imu_rotation")
            if not single:
                raise InvalidInput("imu_rotation must be one (3, 3) rotation matrix")
            object.__setattr__(self, "imu_rotation", rotation[0])
        mode = {True: "yes", False: "no"}.get(self.estimate_scale, self.estimate_scale)
        if mode not in SCALE_MODES:
            raise InvalidInput(
                f"estimate_scale must be one of {', '.join(SCALE_MODES)} (or a bool), got "
                f"{self.estimate_scale!r}"
            )
        object.__setattr__(self, "estimate_scale", mode)
        if self.wrench_noise is not None and not isinstance(self.wrench_noise, SensorNoise):
            raise InvalidInput(
                f"wrench_noise must be an ftkin.SensorNoise, got {type(self.wrench_noise).__name__}"
            )
        if self.accel_noise is not None:
            noise = np.broadcast_to(as_float_array(self.accel_noise, "accel_noise"), (3,)).copy()
            if not np.all(np.isfinite(noise) & (noise > 0.0) & (noise < 100.0)):
                raise InvalidInput(
                    f"accel_noise must be finite, positive and below 100 m/s², got {noise}"
                )
            object.__setattr__(self, "accel_noise", noise)
        if self.imu_position is not None:
            position = as_vector(self.imu_position, 3, "imu_position [m]")
            if np.linalg.norm(position) > 1.0:
                raise InvalidInput(
                    f"imu_position is {np.linalg.norm(position):.3g} m from the sensor origin; "
                    "expected metres within 1 m (millimetres given?)"
                )
            object.__setattr__(self, "imu_position", position)

    @classmethod
    def from_keywords(cls, options=None, **keywords) -> "ImuCalibrationOptions":
        """``options`` (an :class:`ImuCalibrationOptions`, a default ``CalibrationOptions`` or
        None) with ``keywords`` replacing its fields.
        """
        known = {f.name for f in fields(cls)}
        if options is not None and not isinstance(options, cls):
            options = _from_calibration_options(options)
        unknown = set(keywords) - known
        if unknown:
            raise InvalidInput(
                f"unknown option(s) for a calibration from the IMU: {', '.join(sorted(unknown))}; "
                f"expected {', '.join(sorted(known))}"
            )
        return replace(options or cls(), **keywords)


def _from_calibration_options(options) -> ImuCalibrationOptions:
    """An FK ``CalibrationOptions`` carries only its noise over; any other setting is refused."""
    from .estimate import CalibrationOptions  # the FK options: imported where used (a cycle)

    if not isinstance(options, CalibrationOptions):
        raise InvalidInput(
            f"options must be an ftkin ImuCalibrationOptions, got {type(options).__name__}"
        )
    default = CalibrationOptions()
    changed = [
        f.name
        for f in fields(CalibrationOptions)
        if f.name not in ("noise", "g") and getattr(options, f.name) != getattr(default, f.name)
    ]
    if changed:
        raise InvalidInput(
            f"{', '.join(changed)}: not options of a calibration from the IMU (samples from "
            "Samples.from_imu); use ImuCalibrationOptions"
        )
    return ImuCalibrationOptions(wrench_noise=options.noise)


def _layout(rotation_free: bool, scale_free: tuple[int, ...]) -> tuple[str, ...]:
    names = WRENCH_NAMES + (IMU_ROTATION_NAMES if rotation_free else ()) + ACCEL_BIAS_NAMES
    return names + tuple(ACCEL_SCALE_NAMES[k] for k in scale_free)


def tangent_bases(directions: np.ndarray) -> np.ndarray:
    """``(P, 3, 2)`` orthonormal bases of the planes perpendicular to unit ``directions``."""
    helper = np.where(np.abs(directions[:, [0]]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    first = np.cross(directions, helper)
    first /= np.linalg.norm(first, axis=1)[:, None]
    return np.stack([first, np.cross(directions, first)], axis=2)


@dataclass(frozen=True)
class ImuStaticProblem:
    """The whitened least squares of the static IMU calibration (inspectable on its own).

    Parameters ``x = [F0, M0, m, c, δ (if free), b, s_free, e (2P)]`` (:attr:`names`).

    Attributes:
        accel: ``(P, 3)`` mean accelerometer reading per pose [m/s²].
        wrenches: ``(P, 6)`` mean raw wrench per pose [N, N·m].
        counts: ``(P,)`` readings per pose.
        noise: ``(9,)`` per-reading noise ``[accel (3) m/s², force (3) N, torque (3) N·m]``.
        g: Magnitude of gravity [m/s²].
        rotation0: ``R0`` ``(3, 3)``: ``R_SI = R0 Exp(δ)`` (δ fixed at zero when not free).
        directions0: ``(P, 3)`` unit directions at ``e = 0``.
        rotation_free: Whether ``δ`` is estimated.
        scale_free: Which scale components are estimated.
    """

    accel: np.ndarray
    wrenches: np.ndarray
    counts: np.ndarray
    noise: np.ndarray
    g: float
    rotation0: np.ndarray
    directions0: np.ndarray
    rotation_free: bool = True
    scale_free: tuple[int, ...] = ()
    tangents: np.ndarray = field(init=False, repr=False)

    def __post_init__(self):
        object.__setattr__(self, "tangents", tangent_bases(self.directions0))

    @property
    def names(self) -> tuple[str, ...]:
        """The global parameters' names (the directions follow them)."""
        return _layout(self.rotation_free, self.scale_free)

    @property
    def global_count(self) -> int:
        return len(self.names)

    @property
    def parameter_count(self) -> int:
        return self.global_count + 2 * len(self.accel)

    @property
    def weights(self) -> np.ndarray:
        """``(P, 9)`` whitening ``sqrt(n_i) / σ``."""
        return np.sqrt(self.counts)[:, None] / self.noise[None, :]

    def unpack(self, x: np.ndarray) -> dict:
        """The parameters of ``x`` by name: ``F0, M0, m, c, delta, b, s, e``."""
        i = 10
        delta = np.zeros(3)
        if self.rotation_free:
            delta, i = x[i : i + 3], i + 3
        bias, i = x[i : i + 3], i + 3
        scale = np.zeros(3)
        scale[list(self.scale_free)] = x[i : i + len(self.scale_free)]
        i += len(self.scale_free)
        return {
            "F0": x[0:3],
            "M0": x[3:6],
            "m": float(x[6]),
            "c": x[7:10],
            "delta": delta,
            "b": bias,
            "s": scale,
            "e": x[i:].reshape(-1, 2),
        }

    def rotation(self, x: np.ndarray) -> np.ndarray:
        """``R_SI`` at ``x``."""
        return self.rotation0 @ exp_so3(self.unpack(x)["delta"])

    def directions(self, e: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Unit directions ``(P, 3)`` at tangent increments ``e`` ``(P, 2)``, and the norms of
        ``u0 + T e`` before normalising.
        """
        raw = self.directions0 + np.einsum("pij,pj->pi", self.tangents, e)
        norms = np.linalg.norm(raw, axis=1)
        return raw / norms[:, None], norms

    def predict(self, x: np.ndarray) -> np.ndarray:
        """``(P, 9)`` predicted ``[a, F, M]`` per pose."""
        p = self.unpack(x)
        units, _ = self.directions(p["e"])
        force = self.g * units @ self.rotation(x).T  # f_S = g R_SI u
        accel = (1.0 + p["s"]) * self.g * units + p["b"]
        wrench = predict_imu(
            np.concatenate([p["F0"], p["M0"]]), point_mass_parameters(p["m"], p["c"]), force
        )
        return np.concatenate([accel, wrench], axis=1)

    def residuals(self, x: np.ndarray) -> np.ndarray:
        """``(P, 9)`` measured minus predicted."""
        return np.concatenate([self.accel, self.wrenches], axis=1) - self.predict(x)

    def jacobian(self, x: np.ndarray) -> np.ndarray:
        """``(P, 9, n)`` derivative of :meth:`predict` with respect to ``x``."""
        p = self.unpack(x)
        count, g = len(self.accel), self.g
        units, norms = self.directions(p["e"])
        rotation = self.rotation(x)
        force = g * units @ rotation.T  # v = g R u (P, 3)
        projector = np.eye(3) - units[:, :, None] * units[:, None, :]
        d_units = projector @ self.tangents / norms[:, None, None]  # (P, 3, 2)
        d_force_e = g * rotation @ d_units  # (P, 3, 2)
        mass, com = p["m"], p["c"]
        com_skew = skew(com)
        jac = np.zeros((count, 9, self.parameter_count))
        jac[:, 3:9, 0:6] = np.eye(6)  # F0, M0
        jac[:, 3:6, 6] = -force  # ∂F/∂m
        jac[:, 6:9, 6] = -np.cross(com, force)  # ∂M/∂m
        jac[:, 6:9, 7:10] = mass * skew(force)  # ∂M/∂c
        i = 10
        if self.rotation_free:
            d_force_delta = -g * rotation @ skew(units) @ right_jacobian_so3(p["delta"])
            jac[:, 3:6, i : i + 3] = -mass * d_force_delta
            jac[:, 6:9, i : i + 3] = -mass * com_skew @ d_force_delta
            i += 3
        jac[:, 0:3, i : i + 3] = np.eye(3)  # ∂a/∂b
        i += 3
        for k in self.scale_free:
            jac[:, k, i] = g * units[:, k]
            i += 1
        rows = np.arange(count)
        for j in range(2):
            column = i + 2 * rows + j
            jac[rows, 0:3, column] = (1.0 + p["s"]) * g * d_units[:, :, j]
            jac[rows, 3:6, column] = -mass * d_force_e[:, :, j]
            jac[rows, 6:9, column] = -mass * (com_skew @ d_force_e[:, :, j].T).T
        return jac

    def whitened_residuals(self, x: np.ndarray) -> np.ndarray:
        return (self.residuals(x) * self.weights).reshape(-1)

    def whitened_jacobian(self, x: np.ndarray) -> np.ndarray:
        return (self.jacobian(x) * self.weights[:, :, None]).reshape(-1, self.parameter_count)

    def recentred(self, x: np.ndarray) -> "tuple[ImuStaticProblem, np.ndarray]":
        """The same problem with ``R0`` and the directions moved to ``x`` (``δ = 0``, ``e = 0``)."""
        p = self.unpack(x)
        units, _ = self.directions(p["e"])
        problem = replace(self, rotation0=self.rotation(x), directions0=units)
        out = np.array(x, dtype=float)
        if self.rotation_free:
            out[10:13] = 0.0
        out[self.global_count :] = 0.0
        return problem, out


# ------------------------------------------------------------------ closed-form start


def sphere_fit(accel: np.ndarray, g: float, with_scale: bool) -> tuple[np.ndarray, np.ndarray]:
    """Start for the accelerometer's bias ``b`` [m/s²] and scale ``s`` [-] from static means
    ``(P, 3)``: linear least squares of the sphere ``|a − b|² = ρ²`` (``2 a·b + k = |a|²``).

    ``s`` is the isotropic ``ρ / g − 1`` with ``with_scale`` (the joint fit then tells the axes
    apart), else zero. Too few or coplanar directions (rank below four) give zero.
    """
    if len(accel) >= 4:
        design = np.concatenate([2.0 * accel, np.ones((len(accel), 1))], axis=1)
        solution, _, rank, _ = np.linalg.lstsq(design, np.sum(accel**2, axis=1), rcond=None)
        radius_squared = solution[3] + solution[:3] @ solution[:3]
        if rank == 4 and radius_squared > 0.0:
            isotropic = np.sqrt(radius_squared) / g - 1.0 if with_scale else 0.0
            return solution[:3], np.full(3, isotropic)
    return np.zeros(3), np.zeros(3)


def kabsch_start(units: np.ndarray, forces: np.ndarray, g: float):
    """``R_SI``, ``m`` [kg], ``F0`` [N] from unit directions ``(P, 3)`` and forces ``(P, 3)``.

    ``F_i = F0 − m g R u_i``: the rotation best mapping the centred ``g u_i`` onto the centred
    ``−F_i`` (Kabsch, det = +1).

    Raises:
        SuspectConvention: the data fit a mirrored map far better (a negated accelerometer or
            wrench, or a left-handed axis).
    """
    centred_units = g * (units - units.mean(axis=0))
    centred_forces = -(forces - forces.mean(axis=0))
    cross = centred_forces.T @ centred_units  # m R Σ x xᵀ
    left, singular, right_t = np.linalg.svd(cross)
    mirrored = np.linalg.det(left @ right_t) < 0.0
    if mirrored and singular[2] > 0.1 * singular[0]:
        raise SuspectConvention(
            "the forces follow the accelerometer through a mirror, not a rotation: the "
            "accelerometer reports the acceleration (−g upward at rest) instead of the specific "
            "force, the wrench is the reaction instead of the load on the sensor, or one axis of "
            "either is reversed; negate the accelerometer (or the wrench) and calibrate again",
            explanations=[
                "an accelerometer at rest must read +g upward (specific force)",
                "a raw reading is the load on the sensor (a tool hanging below pulls it down)",
            ],
            fixes=["negate specific_force (ax, ay, az)", "negate the wrench (sensor_sign -1)"],
        )
    rotation = left @ np.diag([1.0, 1.0, -1.0 if mirrored else 1.0]) @ right_t
    spread = float(np.sum(centred_units**2))
    mass = float(np.sum(centred_forces * (centred_units @ rotation.T))) / max(spread, 1e-300)
    force_offset = forces.mean(axis=0) + mass * g * rotation @ units.mean(axis=0)
    return rotation, mass, force_offset


def given_rotation_start(units: np.ndarray, forces: np.ndarray, g: float, rotation: np.ndarray):
    """``m`` [kg] and ``F0`` [N] at a given ``R_SI``: least squares of ``F = F0 − m g R u``."""
    directions = g * units @ rotation.T
    design = np.concatenate(
        [np.broadcast_to(np.eye(3), (len(units), 3, 3)), -directions[:, :, None]], axis=2
    ).reshape(-1, 4)
    solution = np.linalg.lstsq(design, forces.reshape(-1), rcond=None)[0]
    return float(solution[3]), solution[:3]


def torque_start(force_in_sensor: np.ndarray, torques: np.ndarray, mass: float):
    """``M0`` [N·m] and ``c`` [m] from ``M = M0 + f_S × (m c)`` (linear least squares)."""
    design = np.concatenate(
        [np.broadcast_to(np.eye(3), (len(torques), 3, 3)), skew(force_in_sensor)], axis=2
    ).reshape(-1, 6)
    solution = np.linalg.lstsq(design, torques.reshape(-1), rcond=None)[0]
    return solution[:3], solution[3:] / mass


def start(poses: ImuPoseAverages, g: float, options: ImuCalibrationOptions, scale_free):
    """The closed-form start: ``(x0 without directions, R0, directions0)``."""
    bias, scale = sphere_fit(poses.specific_force, g, bool(scale_free))
    scale = np.where(np.isin(np.arange(3), scale_free), scale, 0.0)
    corrected = corrected_specific_force(poses.specific_force, bias, scale)
    units = corrected / np.linalg.norm(corrected, axis=1)[:, None]
    forces = poses.wrenches[:, :3]
    if options.imu_rotation is None:
        rotation, mass, force_offset = kabsch_start(units, forces, g)
    else:
        rotation = options.imu_rotation
        mass, force_offset = given_rotation_start(units, forces, g, rotation)
    if not mass > 0.0:
        raise SuspectConvention(
            f"the estimated tool mass is {mass:.4g} kg (not positive): with the given imu_rotation "
            "the forces point up where the accelerometer says down; is R_SI transposed (sensor → "
            "IMU), the accelerometer negated, or the wrench the reaction?",
            fixes=["pass R_SI (IMU → sensor)", "negate the accelerometer", "negate the wrench"],
        )
    torque_offset, com = torque_start(g * units @ rotation.T, poses.wrenches[:, 3:], mass)
    x0 = np.concatenate(
        [force_offset, torque_offset, [mass], com]
        + ([np.zeros(3)] if options.imu_rotation is None else [])
        + [bias, scale[list(scale_free)]]
    )
    return x0, rotation, units


# ------------------------------------------------------------------------- checks


def weakest_direction(problem: ImuStaticProblem, x: np.ndarray) -> tuple[float, list[str]]:
    """Smallest relative singular value of the column-normalised whitened Jacobian, and the global
    parameters its open directions involve: entries above 0.3 of the largest in any direction
    below :data:`~ftkin.calibration.observability.MIN_RELATIVE_SINGULAR_VALUE` (else the weakest).
    """
    jac = problem.whitened_jacobian(x)
    scale = np.linalg.norm(jac, axis=0)
    scale[scale == 0.0] = 1.0
    _, singular, vt = np.linalg.svd(jac / scale, full_matrices=False)
    relative = singular / singular[0]
    open_rows = np.flatnonzero(relative < MIN_RELATIVE_SINGULAR_VALUE)
    involved = []
    for row in open_rows if len(open_rows) else [len(relative) - 1]:
        weakest = np.abs(vt[row, : problem.global_count])
        if weakest.max() > 0.0:
            picked = np.flatnonzero(weakest > 0.3 * weakest.max())
            involved += [problem.names[i] for i in picked if problem.names[i] not in involved]
    return float(relative[-1]), involved


def check_observable(problem: ImuStaticProblem, x: np.ndarray) -> None:
    """Refuse a pose set that leaves a parameter open (see the module docstring).

    Raises:
        UnobservableParameters: naming the parameters of the weakest direction (the accelerometer
            bias with the offsets it trades against, a scale, the rotation, ...).
    """
    relative, involved = weakest_direction(problem, x)
    if relative >= MIN_RELATIVE_SINGULAR_VALUE:
        return
    raise UnobservableParameters(
        involved,
        f"{POSES_NEEDED} (smallest relative singular value {relative:.1e}, need at least "
        f"{MIN_RELATIVE_SINGULAR_VALUE:.0e})",
    )


# ---------------------------------------------------------------------------- fit


def _drop_open_scale(problem, x, options: ImuCalibrationOptions, notes: list) -> bool:
    """With ``estimate_scale="auto"``: True (and a note naming them) when the weakest direction
    at ``x`` is degenerate and involves scale components, which are then left out."""
    if options.estimate_scale != "auto" or not problem.scale_free:
        return False
    relative, involved = weakest_direction(problem, x)
    scale_names = [name for name in involved if name.startswith("accel_scale")]
    if relative >= MIN_RELATIVE_SINGULAR_VALUE or not scale_names:
        return False
    notes.append(
        f"{', '.join(scale_names)} not determined by these poses: taken as 0 (gravity never seen "
        "along both signs of that axis)"
    )
    return True


def _solve(problem: ImuStaticProblem, x0: np.ndarray) -> np.ndarray:
    from scipy.optimize import least_squares  # scipy.optimize loads where it is used

    return least_squares(
        problem.whitened_residuals,
        x0,
        jac=lambda x: -problem.whitened_jacobian(x),
        method="lm",
        x_scale="jac",
        xtol=1e-12,
        ftol=1e-12,
        gtol=1e-12,
    ).x


def _noise_from_spread(poses: ImuPoseAverages) -> np.ndarray | None:
    """``(9,)`` pooled spread of repeated readings, or None with fewer than 5 degrees of freedom."""
    repeated = poses.counts > 1
    dof = float(np.sum(poses.counts[repeated] - 1))
    if dof < 5:
        return None
    spread = np.concatenate([poses.accel_spread, poses.wrench_spread], axis=1)[repeated]
    std = np.sqrt(np.sum((poses.counts[repeated] - 1)[:, None] * spread**2, axis=0) / dof)
    return std if np.all(std > 0.0) else None


_GROUPS = (slice(0, 3), slice(3, 6), slice(6, 9))


def _noise_from_residuals(problem: ImuStaticProblem, x: np.ndarray, floor: np.ndarray):
    """``(9,)`` per-reading noise, accelerometer, force and torque each pooled, corrected by the
    leverages."""
    jac = problem.whitened_jacobian(x)
    hat = np.einsum("ij,ji->i", jac, np.linalg.pinv(jac.T @ jac, hermitian=True) @ jac.T)
    dof = np.clip(1.0 - hat, 1e-9, 1.0).reshape(-1, 9)
    squares = problem.residuals(x) ** 2 * problem.counts[:, None]
    std = [np.sqrt(np.sum(squares[:, part]) / np.sum(dof[:, part])) for part in _GROUPS]
    return np.maximum(np.repeat(std, 3), floor)


def _floor(poses: ImuPoseAverages, g: float) -> np.ndarray:
    return np.concatenate([np.full(3, 1e-7 * g), noise_floor(poses.wrenches)])


@dataclass(frozen=True)
class ImuStaticFit:
    """What :func:`fit_imu_static` found.

    Attributes:
        problem: The final problem (recentred: ``x`` has ``δ = 0``, ``e = 0``).
        x: The parameters at the solution.
        covariance: ``(n, n)`` covariance of the global parameters (directions marginalised).
        noise_source: ``"given"``, ``"spread"`` or ``"residuals"``.
        notes: What the fit decided on its own (a scale left out).
    """

    problem: ImuStaticProblem
    x: np.ndarray
    covariance: np.ndarray
    noise_source: str
    notes: tuple[str, ...]

    @property
    def parameters(self) -> dict:
        return self.problem.unpack(self.x)


def fit_imu_static(
    poses: ImuPoseAverages, g: float, options: ImuCalibrationOptions | None = None
) -> ImuStaticFit:
    """The joint maximum-likelihood fit of the static IMU calibration (module docstring).

    Raises:
        UnobservableParameters: fewer than :data:`MIN_IMU_POSES` poses, or poses that leave a
            parameter open (named).
        SuspectConvention: the data fit a mirrored accelerometer or wrench.
    """
    options = options or ImuCalibrationOptions()
    if len(poses) < MIN_IMU_POSES:
        raise UnobservableParameters(
            ["force_offset", "torque_offset", "tool_mass", "center_of_mass", "accel_bias"],
            f"{len(poses)} static pose(s); the IMU calibration needs at least {MIN_IMU_POSES} "
            f"(12 recommended): {POSES_NEEDED}",
        )
    notes = []
    scale_free = (0, 1, 2) if options.estimate_scale != "no" else ()
    if options.estimate_scale == "auto" and len(poses) < MIN_SCALE_POSES:
        scale_free = ()
        notes.append(
            f"accelerometer scale not estimated ({len(poses)} poses, fewer than "
            f"{MIN_SCALE_POSES}): taken as exact"
        )
    fixed = np.repeat([options.accel_noise is not None, options.wrench_noise is not None], [3, 6])
    spread = None if fixed.all() else _noise_from_spread(poses)
    noise = np.ones(9) if spread is None else spread
    if options.accel_noise is not None:
        noise[0:3] = options.accel_noise
    if options.wrench_noise is not None:
        noise[3:9] = options.wrench_noise.channel_std
    source = "given" if fixed.all() else ("spread" if spread is not None else "residuals")

    def from_residuals(problem, x):  # the given groups stay as given
        return np.where(fixed, noise, _noise_from_residuals(problem, x, _floor(poses, g)))

    while True:  # at the start, then at the solution: a scale the poses leave open is dropped
        x0, rotation0, units = start(poses, g, options, scale_free)
        problem = ImuStaticProblem(
            poses.specific_force,
            poses.wrenches,
            np.asarray(poses.counts, dtype=float),
            noise,
            g,
            rotation0,
            units,
            options.imu_rotation is None,
            scale_free,
        )
        x0 = np.concatenate([x0, np.zeros(2 * len(poses))])
        if source == "residuals":  # rough weights before the check: unit noise mixes units
            problem = replace(problem, noise=from_residuals(problem, x0))
        if _drop_open_scale(problem, x0, options, notes):
            scale_free = tuple(k for k in scale_free if ACCEL_SCALE_NAMES[k] not in notes[-1])
            continue
        check_observable(problem, x0)
        x = _solve(problem, x0)
        for _ in range(NOISE_PASSES if source == "residuals" else 0):
            estimate = from_residuals(problem, x)
            settled = np.allclose(estimate, problem.noise, rtol=1e-2, atol=0.0)
            problem = replace(problem, noise=estimate)
            if settled:
                break
            x = _solve(problem, x)
        problem, x = problem.recentred(x)
        # the start's directions can hide a degeneracy that holds at the measured ones
        if _drop_open_scale(problem, x, options, notes):
            scale_free = tuple(k for k in scale_free if ACCEL_SCALE_NAMES[k] not in notes[-1])
            continue
        check_observable(problem, x)
        break
    jac = problem.whitened_jacobian(x)
    information = jac.T @ jac
    scale = np.sqrt(np.maximum(np.diag(information), 1e-300))
    values, vectors = np.linalg.eigh(information / np.outer(scale, scale))
    if values[0] <= 1e-12 * values[-1]:
        weakest = np.abs(vectors[: problem.global_count, 0])
        raise UnobservableParameters(
            [problem.names[i] for i in np.flatnonzero(weakest > 0.3 * weakest.max())],
            f"the information at the solution is singular: {POSES_NEEDED}",
        )
    covariance = ((vectors / values) @ vectors.T) / np.outer(scale, scale)
    count = problem.global_count
    return ImuStaticFit(problem, x, covariance[:count, :count], source, tuple(notes))


# ---------------------------------------------------------------------- the result


def _covariance_in_sensor_axes(fit: ImuStaticFit) -> np.ndarray:
    """The global covariance with the rotation increment turned into the sensor's axes
    (``R Exp(δ) = Exp(R δ) R``)."""
    covariance, problem = fit.covariance.copy(), fit.problem
    if problem.rotation_free:
        transform = np.eye(len(covariance))
        transform[10:13, 10:13] = problem.rotation0
        covariance = transform @ covariance @ transform.T
    return covariance


def theta_covariance(covariance: np.ndarray, g: float) -> np.ndarray:
    """``(12, 12)`` covariance over ``[a, F0, M0, P]`` with ``a = [0, 0, −m g]`` from the global
    covariance (its first ten rows ``[F0, M0, m, c]``)."""
    transform = np.zeros((12, len(covariance)))
    transform[2, 6] = -g  # a_z = −m g
    transform[3:9, 0:6] = np.eye(6)
    transform[9:12, 7:10] = np.eye(3)
    return transform @ covariance @ transform.T


def calibrate_imu(samples: ImuSamples, options=None, **keywords) -> ImuCalibrationResult:
    """Calibrate from static poses with the sensor's own IMU: no arm, no orientation.

    Args:
        samples: :class:`~ftkin.calibration.imu_samples.ImuSamples`
            (:meth:`ftkin.Samples.from_imu`); readings sharing a pose id are averaged first.
        options: An :class:`ImuCalibrationOptions` (default: all defaults).
        **keywords: Its fields, given directly.

    Returns:
        A frozen :class:`~ftkin.calibration.imu_result.ImuCalibrationResult`.

    Raises:
        UnobservableParameters: the poses leave a parameter open (fewer than four, or gravity
            not seen along every IMU direction: the accelerometer bias and ``F0`` are then named).
        SuspectConvention: a mirrored accelerometer or wrench, or a non-positive mass.
        InvalidInput: an unknown option.
    """
    if not isinstance(samples, ImuSamples):
        raise InvalidInput(
            f"samples must be ftkin ImuSamples (Samples.from_imu), got {type(samples).__name__}"
        )
    given_g = keywords.pop("g", getattr(options, "g", samples.g))
    if not np.isclose(float(given_g), samples.g, rtol=1e-12):
        raise InvalidInput(
            f"g = {given_g} m/s² differs from the samples' {samples.g:g} m/s²: give it once, to "
            "Samples.from_imu(..., g=...)"
        )
    options = ImuCalibrationOptions.from_keywords(options, **keywords)
    poses = samples.pose_averages()
    g = samples.g
    fit = fit_imu_static(poses, g, options)
    p = fit.parameters
    rotation = fit.problem.rotation0
    bias_wrench = np.concatenate([p["F0"], p["M0"]])
    measured = specific_force_at_rest(poses.specific_force, rotation, p["b"], p["s"])
    residuals = poses.wrenches - predict_imu(
        bias_wrench, point_mass_parameters(p["m"], p["c"]), measured
    )
    covariance = _covariance_in_sensor_axes(fit)
    chi_square = float(np.sum(fit.problem.whitened_residuals(fit.x) ** 2))
    dof = 9 * len(poses) - fit.problem.parameter_count
    warnings = list(fit.notes)
    for note in warnings:
        logger.warning("%s", note)
    return ImuCalibrationResult(
        force_offset=p["F0"],
        torque_offset=p["M0"],
        gravity_in_base=np.array([0.0, 0.0, -p["m"] * g]),
        center_of_mass=p["c"],
        g=g,
        method="imu",
        pose_ids=poses.pose_ids,
        pose_wrenches=poses.wrenches,
        residuals=residuals,
        sample_count=int(np.sum(poses.counts)),
        covariance=theta_covariance(covariance, g),
        imu_rotation=rotation,
        accel_bias=p["b"],
        accel_scale=p["s"],
        scale_estimated=tuple(k in fit.problem.scale_free for k in range(3)),
        imu_position=options.imu_position,
        imu_position_source=None if options.imu_position is None else "given",
        parameter_names=fit.problem.names,
        parameter_covariance=covariance,
        accel_std=fit.problem.noise[0:3],
        chi_square=chi_square,
        dof=int(dof),
        imu_warnings=tuple(warnings),
    )


def specific_force_at_rest(accel: np.ndarray, rotation, bias, scale) -> np.ndarray:
    """``f_S = R_SI (a − b) ⊘ (1 + s)`` ``(N, 3)`` [m/s²] (no lever arm: at rest)."""
    return corrected_specific_force(accel, bias, scale) @ np.asarray(rotation).T
