"""Excitation trajectories for the dynamic calibration (Swevers et al. 1997).

Each joint follows a periodic finite Fourier series of base frequency
``ω = 2π / period`` [rad/s] with ``K`` harmonics::

    dq_j(t) = Σ_k a_jk cos(kωt) + b_jk sin(kωt)
    q_j(t)  = q0_j + Σ_k (a_jk sin(kωt) − b_jk cos(kωt)) / (kω)

with ``Σ_k a_jk = 0`` and ``Σ_k k b_jk = 0`` so that the motion starts (and, being
periodic, ends every period) at rest. :func:`plan_excitation` chooses the
coefficients that maximise ``log det`` of the whitened information of the
linear identification problem (bias and the ten inertial parameters,
:mod:`ftkin.calibration.dynamic_fit`), over random starts followed by a
local search (a (1+1) evolution strategy: the limit scaling and the
collision penalty make the cost non-smooth, which stalls gradient methods). Joint position, velocity
and acceleration limits hold by
construction (every candidate is scaled into them); the floor and
self-collision are checked on a grid (:class:`~ftkin.planning.constraints.FeasibilityChecker`),
violations cost a penalty during the search, and the returned plan is
checked on a fine grid.
"""

import dataclasses
from dataclasses import dataclass, field

import numpy as np

from ..calibration.dynamic_fit import DynamicProblem
from ..calibration.information import SensorNoise
from ..calibration.model import STANDARD_GRAVITY
from ..calibration.regressor import body_regressor, sensor_motion
from ..exceptions import InvalidInput
from ..validation import as_float_array, as_positive, from_fields, set_checked, whole_number
from .constraints import FeasibilityChecker, PoseConstraints

DEFAULT_ACCELERATION_LIMIT = 10.0
"""Default joint acceleration limit [rad/s²] (URDFs carry none)."""

DEFAULT_AMPLITUDE = 0.8
"""Default largest excursion of each joint from the centre configuration [rad]."""

DEFAULT_VELOCITY_FRACTION = 0.5
"""Default fraction of the URDF velocity limits used."""

MAX_HARMONICS = 100
"""Most harmonics an :class:`ExcitationSpec` takes (each adds ``2·nq`` coefficients to optimise)."""

_PENALTY = 1e3


@dataclass(frozen=True)
class FourierTrajectory:
    """A periodic joint trajectory; see the module docstring.

    Attributes:
        period: [s].
        offsets: ``(nq,)`` ``q0`` [rad].
        cosine: ``(nq, K)`` ``a`` [rad/s].
        sine: ``(nq, K)`` ``b`` [rad/s].
    """

    period: float
    offsets: np.ndarray
    cosine: np.ndarray
    sine: np.ndarray

    def evaluate(self, times) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``q`` [rad], ``dq`` [rad/s], ``ddq`` [rad/s²], each ``(N, nq)``, at ``(N,)`` times
        [s].
        """
        k_omega = 2.0 * np.pi / self.period * np.arange(1, self.cosine.shape[1] + 1)  # [rad/s]
        phase = np.outer(np.asarray(times, dtype=float), k_omega)
        cos, sin = np.cos(phase), np.sin(phase)
        return (
            self.offsets + (sin / k_omega) @ self.cosine.T - (cos / k_omega) @ self.sine.T,
            cos @ self.cosine.T + sin @ self.sine.T,
            (-sin * k_omega) @ self.cosine.T + (cos * k_omega) @ self.sine.T,
        )


@dataclass(frozen=True)
class ExcitationPlan:
    """A sampled excitation trajectory and its predicted information.

    Attributes:
        trajectory: The Fourier series.
        joint_names: In ``q`` order.
        times: ``(N,)`` [s], at the requested rate.
        joint_positions, joint_velocities, joint_accelerations: ``(N, nq)`` [rad, rad/s, rad/s²].
        log_det: ``log det`` of the normalized whitened information per period.
        condition_number: Of that information (normalized).
        optimized: False for a random (unoptimized) Fourier trajectory.
    """

    trajectory: FourierTrajectory
    joint_names: list[str]
    times: np.ndarray
    joint_positions: np.ndarray
    joint_velocities: np.ndarray
    joint_accelerations: np.ndarray
    log_det: float
    condition_number: float
    optimized: bool

    def table(self) -> tuple[list[str], np.ndarray]:
        """Header and ``(N, 1 + 3 nq)`` rows: ``t``, joint positions, then ``<joint>_vel`` and
        ``<joint>_acc``.
        """
        return [
            "t",
            *self.joint_names,
            *(f"{n}_vel" for n in self.joint_names),
            *(f"{n}_acc" for n in self.joint_names),
        ], np.column_stack(
            [self.times, self.joint_positions, self.joint_velocities, self.joint_accelerations]
        )


def _information(arm, q, dq, ddq, noise: SensorNoise) -> np.ndarray:
    rotations, velocities, accelerations = sensor_motion(arm, q, dq, ddq)
    problem = DynamicProblem(
        np.zeros((len(q), 6)),
        rotations,
        body_regressor(velocities, accelerations),
        noise.channel_std,
        STANDARD_GRAVITY,
    )
    jac = problem.whitened_jacobian(np.eye(18)[8])  # x: zero but x[8] = 1
    jac = np.delete(jac, [6, 7], axis=1)  # tilt: needs the (unknown) mass; the rest is linear
    return jac.T @ jac


def _log_det(information: np.ndarray) -> tuple[float, float]:
    scale = np.sqrt(np.maximum(np.diag(information), 1e-300))
    values = np.linalg.eigvalsh(information / np.outer(scale, scale))
    if values[0] <= 0.0:
        return -np.inf, np.inf
    return float(np.sum(np.log(values)) + 2.0 * np.sum(np.log(scale))), float(
        values[-1] / values[0]
    )


@dataclass(frozen=True, eq=False)
class ExcitationSpec:
    """What excitation to plan (see :func:`plan_excitation`).

    Attributes:
        duration: Length of the recording [s].
        rate: Sample rate of the written trajectory [Hz].
        period: Period of the Fourier series [s] (None: ``duration``).
        harmonics: Number of harmonics ``K`` (2 to :data:`MAX_HARMONICS`).
        velocity_fraction: Fraction of the URDF joint velocity limits allowed.
        acceleration_limit: Joint acceleration limit [rad/s²], scalar or ``(nq,)``.
        center: Configuration the motion swings about [rad] (None: the zero
            configuration clipped into the joint bounds); the optimiser may shift it.
        amplitude: Largest excursion of each joint from the centre [rad], scalar or ``(nq,)``.
        constraints: Joint margin, floor height, self-collision (:class:`PoseConstraints`;
            the tilt limit does not apply to a moving tool and is dropped, and so is the
            clearance kept at calibration poses: the links' convex hulls must not touch, a
            compact wrist's hulls are within 2 cm nearly everywhere).
        noise: Sensor noise weighting the information (None: the paper's sensor).
        candidates: Random starts.
        optimize: False: the first random candidate that meets the constraints,
            unranked and unoptimised (a random Fourier trajectory, for comparisons).
        max_iterations: Cost evaluations of the local optimisation ((1+1) evolution strategy).
        seed: Random seed.
    """

    duration: float
    rate: float = 1000.0
    period: float | None = None
    harmonics: int = 5
    velocity_fraction: float = DEFAULT_VELOCITY_FRACTION
    acceleration_limit: object = DEFAULT_ACCELERATION_LIMIT
    center: object = None
    amplitude: object = DEFAULT_AMPLITUDE
    constraints: PoseConstraints = field(default_factory=PoseConstraints)
    noise: SensorNoise | None = None
    candidates: int = 8
    optimize: bool = True
    max_iterations: int = 150
    seed: int = 0

    def __post_init__(self):
        duration = as_positive(self.duration, "duration")
        if not (
            isinstance(self.constraints, PoseConstraints | None)
            and isinstance(self.noise, SensorNoise | None)
            and isinstance(self.optimize, bool)
        ):
            raise InvalidInput(
                "constraints must be a PoseConstraints or None, noise a SensorNoise or None and "
                f"optimize True or False; got {self.constraints!r}, {self.noise!r}, "
                f"{self.optimize!r}"
            )
        set_checked(
            self,
            duration=duration,
            harmonics=whole_number(self.harmonics, "harmonics", 2, MAX_HARMONICS),
            candidates=whole_number(self.candidates, "candidates", 1),
            max_iterations=whole_number(self.max_iterations, "max_iterations"),
            seed=whole_number(self.seed, "seed"),
            rate=as_positive(self.rate, "rate"),
            period=duration if self.period is None else as_positive(self.period, "period"),
            velocity_fraction=as_positive(self.velocity_fraction, "velocity_fraction"),
            constraints=dataclasses.replace(
                PoseConstraints() if self.constraints is None else self.constraints,
                max_tilt=None,
                clearance=0.0,
            ),
            noise=self.noise if self.noise is not None else SensorNoise.paper(),
        )


def _per_joint(value, nq: int, name: str, unit: str) -> np.ndarray:
    """A positive scalar or ``(nq,)`` as ``(nq,)``."""
    array = as_float_array(value, name)
    if array.shape not in ((), (1,), (nq,)) or not np.all(np.isfinite(array) & (array > 0)):
        raise InvalidInput(f"{name} must be positive [{unit}], a scalar or ({nq},), got {value!r}")
    return np.broadcast_to(array, (nq,)).copy()


class _Design:
    """Maps free coefficients to a trajectory inside the joint limits of ``spec``."""

    def __init__(self, arm, spec: ExcitationSpec):
        self.arm, self.spec, self.nq = arm, spec, arm.nq
        self.checker = checker = FeasibilityChecker(arm, spec.constraints)
        self.velocity_limits = spec.velocity_fraction * arm.velocity_limits
        self.acceleration_limits = _per_joint(
            spec.acceleration_limit, arm.nq, "acceleration_limit", "rad/s²"
        )
        self.center = np.clip(
            np.zeros(arm.nq) if spec.center is None else arm.check_configuration(spec.center),
            checker.lower,
            checker.upper,
        )
        self.amplitude = _per_joint(spec.amplitude, arm.nq, "amplitude", "rad")
        self.grid = np.linspace(0.0, spec.period, 120, endpoint=False)
        self.check_grid = np.linspace(0.0, spec.period, 60, endpoint=False)
        self.size = arm.nq * (2 * spec.harmonics - 2) + arm.nq  # free coefficients and offsets

    def trajectory(self, x: np.ndarray) -> FourierTrajectory:
        nq, free = self.nq, self.spec.harmonics - 1
        a = x[: nq * free].reshape(nq, free)
        b = x[nq * free : 2 * nq * free].reshape(nq, free)
        k = np.arange(1, self.spec.harmonics + 1)
        cosine = np.column_stack([a, -a.sum(axis=1)])  # Σ a_k = 0: dq(0) = 0
        sine = np.column_stack([b, -(b * k[:-1]).sum(axis=1) / k[-1]])  # Σ k b_k = 0: ddq(0) = 0
        unscaled = FourierTrajectory(self.spec.period, np.zeros(nq), cosine, sine)
        q, dq, ddq = unscaled.evaluate(self.grid)
        span = np.maximum(q.max(axis=0) - q.min(axis=0), 1e-12)
        scale = (
            np.minimum.reduce(
                [
                    self.velocity_limits / np.maximum(np.abs(dq).max(axis=0), 1e-12),
                    self.acceleration_limits / np.maximum(np.abs(ddq).max(axis=0), 1e-12),
                    np.minimum(self.checker.upper - self.checker.lower, 2.0 * self.amplitude)
                    / span,
                ]
            )
            * 0.98
        )
        low, high = scale * q.min(axis=0), scale * q.max(axis=0)
        offsets = np.clip(
            self.center + x[2 * nq * free :] - 0.5 * (low + high),
            self.checker.lower - low,
            self.checker.upper - high,
        )
        return FourierTrajectory(
            self.spec.period, offsets, cosine * scale[:, None], sine * scale[:, None]
        )

    def violations(self, trajectory: FourierTrajectory, times) -> int:
        return sum(self.checker.check(row) is None for row in trajectory.evaluate(times)[0])

    def log_det(self, trajectory: FourierTrajectory) -> tuple[float, float]:
        """``log det`` and condition number of the trajectory's information on the grid."""
        return _log_det(_information(self.arm, *trajectory.evaluate(self.grid), self.spec.noise))

    def cost(self, x: np.ndarray) -> float:
        """What the search minimises: −log det, plus a penalty per grid point off the limits."""
        trajectory, constraints = self.trajectory(x), self.spec.constraints
        value, _ = self.log_det(trajectory)
        penalty = 0.0
        if constraints.self_collision or constraints.floor_height is not None:
            penalty = _PENALTY * self.violations(trajectory, self.check_grid)
        return (-value if np.isfinite(value) else 1e6) + penalty


def _evolve(
    cost, x: np.ndarray, iterations: int, rng: np.random.Generator, step: float = 0.3
) -> np.ndarray:
    """(1+1) evolution strategy with the 1/5 success rule: robust to the kinks of the limit scaling
    and penalties.
    """
    best = cost(x)
    for _ in range(iterations):
        candidate = x + rng.normal(0.0, step, x.shape)
        value = cost(candidate)
        if value < best:
            x, best, step = candidate, value, step * 1.5
        else:
            step *= 0.9
    return x


def plan_excitation(arm, spec: ExcitationSpec | float, **options) -> ExcitationPlan:
    """Plan a periodic excitation trajectory for
    :func:`~ftkin.calibration.dynamic.calibrate_dynamic`.

    Args:
        arm: The arm (:class:`~ftkin.kinematics.Arm`).
        spec: An :class:`ExcitationSpec`, or the duration [s] with the spec's other fields as
            keywords (``plan_excitation(arm, 30.0, period=10.0, seed=0)``).

    Raises:
        InvalidInput: bad arguments, or no candidate meets the floor and self-collision constraints.
    """
    if not isinstance(spec, ExcitationSpec):
        spec = from_fields(ExcitationSpec, {"duration": spec, **options}, "plan_excitation")
    elif options:
        raise InvalidInput("give an ExcitationSpec or the duration with keywords, not both")
    design = _Design(arm, spec)
    rng = np.random.default_rng(spec.seed)
    starts = [
        np.concatenate([rng.normal(size=design.size - arm.nq), rng.normal(0.0, 0.05, arm.nq)])
        for _ in range(spec.candidates)
    ]
    # Optimising: best start first. Not optimising: seed order, i.e. a random feasible Fourier
    # trajectory.
    scored = (
        sorted(((design.cost(x), i) for i, x in enumerate(starts)))
        if spec.optimize
        else [(0.0, i) for i in range(len(starts))]
    )
    fine_grid = np.arange(0.0, spec.period, min(0.01, spec.period / 200))
    for _, index in scored:
        x = starts[index]
        if spec.optimize:
            x = _evolve(design.cost, x, spec.max_iterations, rng)
        trajectory = design.trajectory(x)
        if design.violations(trajectory, fine_grid) == 0:
            break
    else:
        raise InvalidInput(
            f"no excitation candidate meets the constraints ({spec.constraints.describe()}); "
            "widen them or try more candidates"
        )
    times = np.arange(int(round(spec.duration * spec.rate))) / spec.rate
    return ExcitationPlan(
        trajectory,
        list(arm.joint_names),
        times,
        *trajectory.evaluate(times),
        *design.log_det(trajectory),  # log det, condition number
        spec.optimize,
    )
