"""Fitting any drift model of :mod:`ftkin.calibration.drift`, and ``drift="auto"``.

Every model extends the maximum-likelihood problem of :mod:`ftkin.calibration.ml`
(per-pose mean readings, per-reading noise ``σ`` per channel) and keeps its
parameters ``θ = [a, F0, M0, P]``, with ``F0``, ``M0`` the bias at the end ``T``
of the recording. One fit serves them all:

* ``φ = [θ, c]`` (``c`` the coefficients of the model's basis, linear) is found
  by Gauss–Newton on the residuals whitened by the random-walk filter of
  :mod:`ftkin.calibration.random_walk` (a model without a walk: rate 0, the
  filter is plain weighting). ``θ``'s covariance is its block of the inverse
  of the whitened information, so the standard errors include what the drift
  costs; with a walk they are conditional on the rates.
* **The noise a drift cannot swallow.** With a walk, the rates [N/√s, N·m/√s]
  (and the noise levels, when neither given nor measured by the spread of
  repeated readings) maximize the *restricted* likelihood
  ``log L − ½ log det(Jᵀ J)`` (``J`` the whitened Jacobian of ``φ``;
  Nelder–Mead on their logarithms after a coarse grid): the plain likelihood
  lets ``φ`` and the walk take the noise's degrees of freedom, and with one
  reading per pose its maximum can sit at zero noise. When the noise still
  cannot be told from the walk (its estimate at the numeric floor, or the
  walk between consecutive poses more than :data:`NOISE_WALK_RATIO` times the
  noise of a pose mean) the walk is not used and the fit says why.
  Without a walk, an estimated noise is ``Σ n e² / Σ (1 − h)`` per group
  (leverages ``h``), iterated with the fit: the same restricted estimate.

``auto`` compares the registered candidates (:func:`~ftkin.calibration.drift.auto_candidates`)
by the Bayesian information criterion ``BIC = −2 log L + k log(6P)`` (``k``
parameters including the estimated noise levels and rates, ``P`` poses): a
drift must pay for itself, so on a constant bias ``none`` wins.
"""

import logging
from dataclasses import dataclass, replace

import numpy as np

from ..exceptions import UnobservableParameters
from .covariance import invert_information
from .drift import BiasDrift, DriftModel, auto_candidates, parse_drift, trend_columns
from .information import SensorNoise
from .ml import RESIDUAL_NOISE_GROUPS, WhitenedFit, pooled_noise
from .model import COMPONENT_NAMES, SensorModel, parameter_jacobian, predict
from .random_walk import log_likelihood, smooth, walk_gains, whiten
from .samples import PoseAverages

logger = logging.getLogger(__name__)

MAX_AUTO_WALK_POSES = 500
"""Above this many poses, ``auto`` leaves the walks out (``drift="random-walk"`` still fits one):
a stream without a pose column makes every reading a pose, and the walk's search would take
minutes.
"""

SEARCH_ITERATIONS = 2
"""Gauss–Newton steps of ``φ`` per likelihood evaluation while the rates are searched
(warm-started)."""

FINAL_ITERATIONS = 20
"""Most Gauss–Newton steps of ``φ`` at the chosen rates and noise."""

NOISE_PASSES = 4
"""Most re-estimations of an estimated noise without a walk (each followed by a refit)."""

RATE_GRID = 10.0 ** np.arange(-4.0, 1.5, 1.0)
"""Multiples of the reference rate (noise of a pose mean over √(pose spacing)) tried before the
Nelder–Mead search."""

MIN_ORIENTATION_POSES = 10
"""Fewest poses for the test that a drift's bias path follows the orientation
(:func:`_follows_orientation`): below, four regressors explain too much by chance."""

ORIENTATION_R2 = 0.9
"""Share of a drift's bias path (in units of the pose-mean noise) that the gravity direction in
the sensor frame must explain for the path to be called a model error."""

MIN_PATH_EXCURSION = 3.0
"""A bias path whose spread is below this many pose-mean noise levels is not tested: it is
within the noise, and a model error that small changes nothing."""

NOISE_WALK_RATIO = 10.0
"""Walk between consecutive poses [multiples of the noise of a pose mean] beyond which an
estimated noise cannot be told from the walk."""


_UNTOLD = (
    "the drift model cannot be told apart from them with these poses and times (record the poses "
    "in a mixed order, or choose a simpler drift model)"
)


@dataclass(frozen=True)
class DriftStart:
    """What the constant-bias fit hands a drift fit.

    Attributes:
        theta: ``(12,)`` ``θ`` of the constant-bias fit.
        channel_std: ``(6,)`` per-reading noise [N, N·m] (a start when estimated).
        noise_source: ``"given"``, ``"spread"`` or ``"residuals"`` (estimated here).
        noise_dof: Degrees of freedom of a given or spread noise (``inf`` if given).
        floor: ``(6,)`` lowest noise an estimate may take [N, N·m].
        floor_given: True when the floor is the user's sensor resolution (then a
            noise on it is a sound estimate, not a collapse).
    """

    theta: np.ndarray
    channel_std: np.ndarray
    noise_source: str
    noise_dof: float
    floor: np.ndarray
    floor_given: bool = False

    @property
    def estimated(self) -> bool:
        """True when the drift fit estimates the noise."""
        return self.noise_source == "residuals"


@dataclass(frozen=True)
class DriftFit(WhitenedFit):
    """A drift model's fit (with the attributes of :class:`~ftkin.calibration.ml.WhitenedFit`,
    ``θ`` with the bias at the end of the recording, the drift parameters marginalized).

    Attributes:
        covariance: ``(12, 12)`` covariance of ``θ`` (the inverse of :attr:`information`).
        parameter_count: Fitted parameters (``θ``, coefficients, rates, estimated noise levels).
        log_likelihood: Gaussian log-likelihood of the pose means at the fit.
        drift: The bias trajectory.
        collapse: Why the noise cannot be told from the walk, or None (a sound fit).
    """

    covariance: np.ndarray
    parameter_count: int
    log_likelihood: float
    drift: BiasDrift
    collapse: str | None = None

    @property
    def bic(self) -> float:
        """Bayesian information criterion ``−2 log L + k log(6P)``."""
        return -2.0 * self.log_likelihood + self.parameter_count * np.log(self.whitened.size)


def _log_likelihood(residuals: np.ndarray, counts: np.ndarray, start: DriftStart) -> float:
    """Gaussian log-likelihood of pose-mean ``residuals`` ``(P, 6)`` read ``counts`` ``(P,)``
    times, at the start's noise or, when the noise is estimated, at its ML value.
    """
    counts = counts[:, None]
    std = start.channel_std
    if start.estimated:
        std = pooled_noise(np.sum(residuals**2 * counts, 0), np.full(6, len(counts)), start.floor)
    variance = std**2 / counts
    return float(-0.5 * np.sum(residuals**2 / variance + np.log(2.0 * np.pi * variance)))


class SortedPoses:
    """Poses in time order, the permutation back, and a model's trend columns."""

    def __init__(self, poses: PoseAverages, model: DriftModel):
        self.order = np.argsort(poses.times, kind="stable")
        self.back = np.argsort(self.order)  # sorted → given pose order
        self.times = np.asarray(poses.times)[self.order]
        self.rotations = poses.rotations[self.order]
        self.wrenches = poses.wrenches[self.order]
        self.counts = np.asarray(poses.counts, dtype=float)[self.order]
        self.scale = float(self.times[-1] - self.times[0]) or 1.0
        self.basis = model.basis((self.times - self.times[-1]) / self.scale)
        self.trend = trend_columns(self.basis)
        self.names = list(COMPONENT_NAMES) + [
            f"drift c{k + 1}[{c}]" for k in range(model.columns) for c in range(6)
        ]

    def raw_residuals(self, phi: np.ndarray) -> np.ndarray:
        """``(P, 6)`` readings minus ``θ``'s prediction minus the trend [N, N·m]."""
        return (
            self.wrenches - predict(self.rotations, phi[:12]) - self.basis @ phi[12:].reshape(-1, 6)
        )


def gauss_newton(data: SortedPoses, phi, std, rate, iterations: int):
    """Gauss–Newton on ``φ = [θ, c]`` at fixed noise ``(6,)`` and walk rates ``(6,)``.

    Returns ``(restricted log L, log L, φ, whitened residuals (P, 6), whitened Jacobian
    (P, 6, n), gains)``. During a search (``iterations ≤ SEARCH_ITERATIONS``) the
    residuals after the last step are linearized, so an evaluation costs one filter
    pass per step.
    """
    gains = walk_gains(data.times, std[None, :] ** 2 / data.counts[:, None], rate)

    def whitened(phi):
        jacobian = parameter_jacobian(data.rotations, phi[0:3], phi[9:12])
        white = whiten(
            gains, np.concatenate([data.raw_residuals(phi)[:, :, None], jacobian, data.trend], 2)
        )
        return white[:, :, 0], white[:, :, 1:]

    for _ in range(iterations):
        residuals, jacobian = whitened(phi)
        step = np.linalg.lstsq(jacobian.reshape(-1, len(phi)), residuals.reshape(-1), rcond=None)[0]
        phi, change = phi + step, jacobian @ step
        if np.sum(change**2) < 1e-12 * (1.0 + np.sum(residuals**2)):
            break
    if iterations <= SEARCH_ITERATIONS:
        residuals = residuals - change
    else:
        residuals, jacobian = whitened(phi)
    flat = jacobian.reshape(-1, len(phi))
    log_l = log_likelihood(gains, residuals)
    restricted = log_l - 0.5 * np.linalg.slogdet(flat.T @ flat)[1]
    return restricted, log_l, phi, residuals, jacobian, gains


def _search_walk(data: SortedPoses, phi, start: DriftStart):
    """Rates (and noise, when estimated) ``(6,)``, ``(6,)`` of maximum restricted likelihood, and
    the ``φ`` found on the way.
    """
    from scipy.optimize import minimize  # scipy loads where it is used (import ftkin stays light)

    std0 = np.asarray(start.channel_std, dtype=float)
    spacing = max(float(np.median(np.diff(data.times))) if len(data.times) > 1 else 1.0, 1e-9)
    # the noise of a pose mean over √(pose spacing)
    reference = np.log(
        [std0[g].mean() / np.sqrt(np.median(data.counts) * spacing) for g in RESIDUAL_NOISE_GROUPS]
    )
    noise_part = np.log([std0[g].mean() for g in RESIDUAL_NOISE_GROUPS]) if start.estimated else []
    best = {"phi": phi, "value": np.inf}

    def unpack(x):
        std = np.maximum(np.repeat(np.exp(x[2:4]), 3), start.floor) if start.estimated else std0
        return np.repeat(np.exp(x[:2]), 3), std

    def objective(x):
        rate, std = unpack(x)
        value, _, phi = gauss_newton(data, best["phi"], std, rate, SEARCH_ITERATIONS)[:3]
        value = -value if np.isfinite(value) else np.inf
        if value < best["value"]:
            best.update(phi=phi, value=value)
        return value

    grid = [objective(np.concatenate([reference + np.log(f), noise_part])) for f in RATE_GRID]
    x0 = np.concatenate([reference + np.log(RATE_GRID[int(np.argmin(grid))]), noise_part])
    solution = minimize(
        objective,
        x0,
        method="Nelder-Mead",
        options={"xatol": 0.05, "fatol": 0.01, "maxfev": 40 * len(x0)},
    )
    return (*unpack(solution.x), best["phi"])


def _collapse(data: SortedPoses, std, rate, start: DriftStart) -> str | None:
    """Why an estimated noise cannot be told from the walk, or None."""
    if not start.estimated or start.floor_given:
        return None
    per_pose = std / np.sqrt(np.median(data.counts))
    step = rate * np.sqrt(max(float(np.median(np.diff(data.times))), 0.0))
    for g, name, unit in zip(RESIDUAL_NOISE_GROUPS, ("force", "torque"), ("N", "N·m")):
        if (
            np.all(std[g] <= start.floor[g] * (1.0 + 1e-3))
            or step[g][0] > NOISE_WALK_RATIO * per_pose[g][0]
        ):
            return (
                f"the {name} noise and the random walk cannot be told apart (noise "
                f"{std[g][0]:.3g} {unit} per reading, walk {step[g][0]:.3g} {unit} between "
                "consecutive poses): the walk would take the noise"
            )
    return None


def _noise_without_walk(data: SortedPoses, phi, start: DriftStart):
    """Gauss–Newton with a leverage-corrected noise re-estimated between passes (if estimated);
    the rates (zero), noise and ``φ``, as :func:`_search_walk` returns them.
    """
    std = np.asarray(start.channel_std, dtype=float)
    for _ in range(NOISE_PASSES if start.estimated else 1):
        _, _, phi, _, jacobian, _ = gauss_newton(data, phi, std, np.zeros(6), FINAL_ITERATIONS)
        if not start.estimated:
            break
        flat = jacobian.reshape(-1, len(phi))
        covariance = invert_information(flat.T @ flat, data.names, _UNTOLD)
        leverage = np.einsum("pki,ij,pkj->pk", jacobian, covariance, jacobian)
        squares = np.sum(data.raw_residuals(phi) ** 2 * data.counts[:, None], axis=0)
        new = pooled_noise(squares, np.sum(1.0 - leverage, axis=0), start.floor)
        converged, std = np.allclose(new, std, rtol=1e-3), new
        if converged:
            break
    return np.zeros(6), std, phi


def fit_drift_model(
    model: DriftModel, poses: PoseAverages, start: DriftStart, selected_by: str = "given"
) -> DriftFit:
    """Fit ``θ`` and the drift ``model`` from the constant-bias ``start`` (see the module)."""
    data = SortedPoses(poses, model)
    phi = np.concatenate([start.theta, np.zeros(6 * model.columns)])
    rate, std, phi = (_search_walk if model.walk else _noise_without_walk)(data, phi, start)
    _, log_l, phi, white, jacobian, gains = gauss_newton(data, phi, std, rate, FINAL_ITERATIONS)
    flat = jacobian.reshape(-1, len(phi))
    covariance = invert_information(flat.T @ flat, data.names, _UNTOLD)
    hat = jacobian @ covariance @ np.transpose(jacobian, (0, 2, 1))
    residuals = data.raw_residuals(phi)
    if start.estimated and not model.walk:  # the likelihood at the ML noise, for the BIC
        log_l = _log_likelihood(residuals, data.counts, start)
    walk, variance = smooth(gains, data.times, residuals, rate)
    rows = np.column_stack([np.ones(len(data.times)), data.basis])
    trend_variance = np.column_stack(
        [
            np.einsum("ni,ij,nj->n", rows, covariance[np.ix_(index, index)], rows)
            for index in (
                [3 + c] + [12 + 6 * k + c for k in range(model.columns)] for c in range(6)
            )
        ]
    )
    coefficients = phi[12:].reshape(-1, 6)
    dof = min(float(np.sum(1.0 - np.einsum("pkk->pk", hat)[:, g])) for g in RESIDUAL_NOISE_GROUPS)
    return DriftFit(
        model=SensorModel.from_vector(phi[:12]),
        noise=SensorNoise(std[:3], std[3:]),
        noise_source=start.noise_source,
        noise_dof=dof if start.estimated else start.noise_dof,
        information=np.linalg.inv(covariance[:12, :12]),
        whitened=white[data.back],
        hat=hat[data.back],
        loss="linear",
        covariance=covariance[:12, :12],
        parameter_count=len(phi) + 2 * model.walk + 2 * start.estimated,
        log_likelihood=log_l,
        drift=BiasDrift(
            model.name,
            selected_by,
            data.times,
            phi[3:9] + data.basis @ coefficients + walk,
            np.sqrt(np.clip(variance + trend_variance, 0.0, None)),
            rate=rate[[0, 3]] if model.walk else None,
            coefficients=coefficients if model.columns else None,
            time_scale=data.scale,
        ),
        collapse=_collapse(data, std, rate, start) if model.walk else None,
    )


def _fit_candidates(models, poses: PoseAverages, start: DriftStart, selected_by: str):
    """Fits and BIC of the candidate ``models`` that can be fitted, and why the others cannot."""
    auto, observations = selected_by == "auto", 6 * len(poses)
    criteria, fits, notes, left_out = {}, {}, [], []
    for model in models:
        count = 12 + 6 * model.columns + 2 * model.walk + 2 * start.estimated
        if model.name == "none":
            log_l = _log_likelihood(
                poses.wrenches - predict(poses.rotations, start.theta),
                np.asarray(poses.counts, dtype=float),
                start,
            )
            criteria["none"] = -2.0 * log_l + count * np.log(observations)
            continue
        if auto and (count > observations - 6 or (model.walk and len(poses) > MAX_AUTO_WALK_POSES)):
            continue  # the walk's filter costs a Python pass per pose and evaluation
        try:
            fit = model.fit(poses, start, selected_by)  # a model's own fit, else the generic one
            if fit is None:
                fit = fit_drift_model(model, poses, start, selected_by)
        except UnobservableParameters:
            if not auto:
                raise
            continue
        if fit.collapse is not None:
            notes.append(f"drift {model.name}: {fit.collapse}")
            continue
        follows = _follows_orientation(poses, fit)
        if follows is not None and auto:  # a model error, not a drift: left out, said once
            left_out.append((model.name, follows))
            continue
        if follows is not None:
            logger.warning("drift %s: %s", model.name, follows)
        fits[model.name], criteria[model.name] = fit, fit.bic
    if left_out:
        names = ", ".join(name for name, _ in left_out)
        logger.warning("drift %s left out: %s", names, left_out[0][1])
    return fits, criteria, notes


def _follows_orientation(poses: PoseAverages, fit: DriftFit) -> str | None:
    """Why the bias path a drift model found is a model error rather than a drift, or None.

    A sensor's drift is a function of time; what a wrong model leaves (a sensor mounted
    otherwise than the URDF says, a wrong sensor frame, a torque unit) is a function of the
    orientation, linear in the gravity direction in the sensor frame ``u = R_BSᵀ a / |a|``. With
    :data:`MIN_ORIENTATION_POSES` poses or more, a path that moves well beyond the noise of a
    pose mean (its spread over :data:`MIN_PATH_EXCURSION` times that noise) and that ``[1, u]``
    explains to :data:`ORIENTATION_R2` or more (pooled over the six channels, each in units of
    its pose-mean noise) follows the orientation, not the clock.
    """
    count = len(poses.pose_ids)
    if count < MIN_ORIENTATION_POSES or fit.drift is None:
        return None
    order = np.argsort(poses.times, kind="stable")
    gravity = fit.model.gravity_in_base
    direction = np.einsum("pji,j->pi", poses.rotations[order], gravity / np.linalg.norm(gravity))
    design = np.column_stack([np.ones(count), direction])
    counts = np.asarray(poses.counts, dtype=float)[order]
    path = fit.drift.bias / (fit.noise.channel_std[None, :] / np.sqrt(counts)[:, None])
    centred = path - path.mean(axis=0)
    total = float(np.sum(centred**2))
    if total < MIN_PATH_EXCURSION**2 * count:
        return None
    coefficients = np.linalg.lstsq(design, path, rcond=None)[0]
    explained = 1.0 - float(np.sum((path - design @ coefficients) ** 2)) / total
    if explained < ORIENTATION_R2:
        return None
    return (
        f"the bias it finds follows the sensor's orientation, not time (the gravity direction "
        f"in the sensor frame explains {100 * explained:.0f} % of it over {count} poses): that "
        "is a model error, not a drift: a sensor mounted otherwise than the URDF says "
        "(estimate_mount='yaw' or 'full', --estimate-mount), a wrong sensor frame, or a unit "
        "or convention of the readings (ftkin doctor)"
    )


def select_drift(models, poses: PoseAverages, start: DriftStart):
    """Fit the candidate drift ``models`` (one given, or several for ``auto``) and keep the best.

    Returns ``(fit or None when the constant bias wins, BIC by candidate (auto), warnings)``.
    A given walk whose noise collapses falls back to ``auto`` among the models without a
    walk, and a warning says why.
    """
    selected_by = "auto" if len(models) > 1 else "given"
    fits, criteria, notes = _fit_candidates(models, poses, start, selected_by)
    if not criteria:  # the one given model collapsed: the models without a walk
        selected_by = "auto"
        fallback = [m for m in map(parse_drift, auto_candidates()) if not m.walk]
        fits, criteria, more = _fit_candidates(fallback, poses, start, selected_by)
        notes += more
    choice = min(criteria, key=criteria.get)
    notes = tuple(
        f"{note}; kept {choice} instead. Record several readings per pose (a pose column), or "
        "give the noise (noise=, --noise-force/--noise-torque) or the sensor resolution "
        "(resolution=, --resolution)"
        for note in notes
    )
    for note in notes:
        logger.warning(note)
    criteria = criteria if selected_by == "auto" else {}
    fit = fits.get(choice)
    if fit is not None and criteria:
        fit = replace(fit, drift=replace(fit.drift, criteria=criteria))
    return fit, criteria, notes
