"""How much of the readings' variation across poses a calibration explains, and the refusal of a
fit that explains almost none of it.

A static calibration explains the readings' change from pose to pose by the tool's weight
turning in the sensor frame. A file whose columns hold other channels than their names say
(forces and torques swapped, channels interleaved) still gives a fit: a tool of a few grams
that explains nothing, which must not be written as a calibration.

:func:`explained_share` is ``1 − Σ r² / Σ (w − w̄)²`` pooled over the poses and the six channels
in N and N·m (``r``: the fit's residuals, ``w̄``: the mean reading). Pooled in SI, the force
channels, which carry the weight, dominate: a tool whose centre of mass sits at the sensor
origin (torques that vary by noise alone) is not refused for it.

:data:`MIN_EXPLAINED` is 0.5: for a right reading of a tool, the share is the tool weight's
variance over the weight's plus the noise's, so less than half means a tool lighter than about
twice the noise of a pose mean, with nothing to calibrate (the compensation would be inside the
noise); right readings of a real tool explain more than 0.9, swapped or interleaved columns
near 0 (the model cannot turn a torque into a force). One exception: when the noise is known
independently (repeated readings per pose, or given) and the residuals are within it (the fit
test passes), the readings hold nothing beyond the noise (no tool on the sensor), which the
fit has explained as well as it can: not refused.
"""

import numpy as np

from ..exceptions import UnexplainedReadings

MIN_EXPLAINED = 0.5
"""Least share of the readings' variation across poses a calibration must explain (see the
module docstring for the reason)."""


def explained_share(wrenches, residuals) -> float:
    """``1 − Σ r² / Σ (w − w̄)²`` over the ``(P, 6)`` pose readings ``wrenches`` [N, N·m] and the
    fit's ``residuals`` [N, N·m]; 1 when the readings do not vary at all."""
    wrenches, residuals = np.asarray(wrenches, float), np.asarray(residuals, float)
    total = float(np.sum((wrenches - wrenches.mean(axis=0)) ** 2))
    return 1.0 if total == 0.0 else 1.0 - float(np.sum(residuals**2)) / total


def check_explained(result) -> None:
    """Raise :class:`~ftkin.exceptions.UnexplainedReadings` when the calibration ``result`` (a
    :class:`~ftkin.calibration.result.CalibrationResult`) explains less than
    :data:`MIN_EXPLAINED` of its readings' variation, unless they are noise alone (see the
    module docstring)."""
    share = explained_share(result.pose_wrenches, result.residuals)
    if share >= MIN_EXPLAINED:
        return
    diagnostics = result.diagnostics
    if (
        diagnostics is not None
        and diagnostics.noise_source in ("given", "spread")
        and diagnostics.fit_ok
    ):
        return  # within a noise known on its own: nothing on the sensor to explain
    raise UnexplainedReadings(
        f"the calibration explains {100 * max(share, 0.0):.0f} % of the readings' variation "
        f"across poses (at least {100 * MIN_EXPLAINED:.0f} % expected; fitted tool weight "
        f"{result.tool_weight:.3g} N): the columns hold other channels than their names say "
        "(forces and torques swapped, channels in another order), the orientations belong to "
        "other readings, or the tool is lighter than the noise. Run 'ftkin doctor' on the "
        "samples (ftkin.io.diagnose_samples), which tries the column mix-ups, and correct the "
        "header; nothing was written",
        share,
        MIN_EXPLAINED,
    )
