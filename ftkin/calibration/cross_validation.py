"""K-fold cross-validation: how well a calibration compensates poses it did not see.

The honest test of a calibration on real data (where the truth is unknown):
the poses are split at random into ``k`` folds; each fold's pose means are
compensated with a calibration fitted to the other ``k − 1`` folds, and the
compensated wrench (raw − bias − tool gravity; the truth is zero, the tool is
free at calibration poses) is collected over all folds. A drift-aware
calibration compensates a held-out pose with its bias at the pose's time
(:meth:`~ftkin.calibration.drift.BiasDrift.bias_at`: between the training
poses it interpolates the smoothed bias). Comparing ``drift="none"`` with
``"auto"`` this way tells whether modelling a drift pays on *this* sensor.

Reading signs and a mount are applied as the calibration says
(:func:`~ftkin.calibration.conventions.as_real_sensor`); every fold is fitted
with the same options.
"""

import logging
from contextlib import contextmanager
from dataclasses import dataclass, field, replace

import numpy as np

from ..exceptions import InvalidInput, UnobservableParameters
from ..validation import whole_number
from .conventions import as_real_sensor
from .samples import Samples

MIN_FOLDS, MAX_FOLDS = 2, 50


@dataclass(frozen=True)
class CrossValidation:
    """Held-out compensation errors per drift setting.

    Attributes:
        folds: Number of folds ``k``.
        pose_count: Poses split among them.
        force_rms: ``{drift setting: RMS over held-out poses of |compensated force|}`` [N].
        torque_rms: ``{drift setting: RMS of |compensated torque|}`` [N·m].
        models: ``{drift setting: drift model each fold's fit took}``.
        seed: Seed of the random split.
    """

    folds: int
    pose_count: int
    force_rms: dict[str, float]
    torque_rms: dict[str, float]
    models: dict[str, tuple[str, ...]] = field(default_factory=dict)
    seed: int = 0

    def report(self) -> str:
        """A table: one row per drift setting, and the ratio to the first."""
        first = next(iter(self.force_rms))
        lines = [
            f"{self.folds}-fold cross-validation over {self.pose_count} poses (seed {self.seed}): "
            "compensated wrench at held-out poses (the truth is zero)",
            f"  {'drift':<22}{'force RMS [N]':>15}{'torque RMS [N·m]':>18}{f'÷ {first}':>10}  "
            "models of the folds",
        ]
        for setting in self.force_rms:
            ratio = self.force_rms[setting] / max(self.force_rms[first], 1e-300)
            models = ", ".join(
                f"{m} ×{self.models[setting].count(m)}"
                for m in sorted(set(self.models.get(setting, ())))
            )
            lines.append(
                f"  {setting:<22}{self.force_rms[setting]:>15.4g}{self.torque_rms[setting]:>18.4g}"
                f"{ratio:>10.2f}  {models}"
            )
        return "\n".join(lines)


def _below_error(record: logging.LogRecord) -> bool:
    return record.levelno >= logging.ERROR


@contextmanager
def _quiet_fits():
    """The folds' fits keep their warnings to themselves: they are about sub-fits, not the user's
    calibration.

    A filter on the calibration loggers (not their level, which another thread may rely on) drops
    the warnings.
    """
    loggers = [
        logging.getLogger(name)
        for name in logging.root.manager.loggerDict
        if name.startswith("ftkin.calibration")
    ]
    for logger in loggers:
        logger.addFilter(_below_error)
    try:
        yield
    finally:
        for logger in loggers:
            logger.removeFilter(_below_error)


def _subset(samples: Samples, mask: np.ndarray) -> Samples:
    per_reading = ("wrenches", "rotations", "pose_ids", "joint_positions", "times")
    values = {name: getattr(samples, name) for name in per_reading}
    return replace(samples, **{k: v[mask] for k, v in values.items() if v is not None})


def _held_out_squares(result, test: Samples) -> np.ndarray:
    """``(P, 2)`` squared compensated force and torque at the held-out poses [N², N²·m²]."""
    poses = as_real_sensor(test, result).pose_averages()
    bias = result.bias if poses.times is None else result.bias_at(poses.times)
    residual = poses.wrenches - result.tool_gravity_wrench(poses.rotations) - bias
    return np.column_stack([np.sum(residual[:, :3] ** 2, 1), np.sum(residual[:, 3:] ** 2, 1)])


def cross_validate(
    samples: Samples,
    drifts=("none", "auto"),
    folds: int = 5,
    seed: int = 0,
    options=None,
    **keywords,
) -> CrossValidation:
    """Compensate each fold's poses with a calibration on the others, for each drift setting.

    Args:
        samples: The calibration samples (several readings per pose are averaged per pose).
        drifts: Drift settings to compare (:func:`~ftkin.calibration.fit_registry.calibrate`'s
            ``drift``).
        folds: Number of folds ``k`` (2..50, at most the number of poses).
        seed: Seed of the random split into folds.
        options: :class:`~ftkin.calibration.fit_options.CalibrationOptions` of every fit (its
            drift replaced by each setting).
        **keywords: Further calibrate options (method, noise, mount, signs, ...), not ``drift``.

    Raises:
        InvalidInput: bad ``folds`` or drift settings, or too few poses for
            ``k`` folds (each training set must determine the parameters).
    """
    from .fit_registry import calibrate  # the fits import the whole estimator: loaded when used

    # refused in this order: each check reads only what the ones before it accepted
    if "drift" in keywords:
        raise InvalidInput("give the drift settings to compare as drifts=(...), not drift=")
    names = tuple(drifts) if isinstance(drifts, list | tuple) else ()
    if not names or not all(isinstance(d, str) for d in names) or len(set(names)) != len(names):
        raise InvalidInput(
            f"drifts must be distinct drift settings (e.g. ('none', 'auto')), got {drifts!r}"
        )
    drifts = names
    if (
        isinstance(folds, bool)
        or not isinstance(folds, int | np.integer)
        or not MIN_FOLDS <= folds <= MAX_FOLDS
    ):
        raise InvalidInput(
            f"folds must be an integer from {MIN_FOLDS} to {MAX_FOLDS}, got {folds!r}"
        )
    if not isinstance(samples, Samples):
        raise InvalidInput(f"samples must be an ftkin.Samples, got {type(samples).__name__}")
    rng = np.random.default_rng(whole_number(seed, "seed"))
    pose_ids, reading_pose = np.unique(samples.pose_ids, return_inverse=True)
    if len(pose_ids) < folds:
        raise InvalidInput(
            f"{len(pose_ids)} poses cannot be split into {folds} folds; use fewer folds"
        )
    # each reading's fold is its pose's, at random
    reading_fold = (rng.permutation(len(pose_ids)) % folds)[reading_pose]
    squares = {drift: [] for drift in drifts}
    models = {drift: [] for drift in drifts}
    for k in range(folds):
        train, test = _subset(samples, reading_fold != k), _subset(samples, reading_fold == k)
        for drift in drifts:
            try:
                with _quiet_fits():
                    result = calibrate(train, options, drift=drift, **keywords)
            except UnobservableParameters as error:
                raise InvalidInput(
                    f"fold {k + 1} of {folds}: the other folds' {len(np.unique(train.pose_ids))} "
                    f"poses cannot determine the parameters ({error}); use fewer folds"
                ) from None
            squares[drift].append(_held_out_squares(result, test))
            models[drift].append(result.drift.model if result.drift is not None else "none")
    rms = {d: np.sqrt(np.mean(np.concatenate(v), axis=0)) for d, v in squares.items()}
    return CrossValidation(
        folds,
        len(pose_ids),
        {d: float(v[0]) for d, v in rms.items()},
        {d: float(v[1]) for d, v in rms.items()},
        {d: tuple(m) for d, m in models.items()},
        seed,
    )
