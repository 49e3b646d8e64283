"""One goodness-of-fit test for every calibration kind: :class:`FitTest`, :func:`fit_test`.

Every fit (static from rotations or joints, with the mount, from the IMU, fused, dynamic from
joints or from the IMU) hands its **whitened residuals** ``r`` (one row per pose or per reading,
one column per channel) and its **whitened Jacobian** ``J``
(:mod:`ftkin.calibration.covariance`) to :func:`fit_test`, which finds:

* ``χ² = Σ r²`` with ``ν = r.size − rank(J)`` degrees of freedom and its p-value: the
  chi-square survival function when the noise was given, the F distribution's
  ``F(ν, ν_noise)`` of ``χ²/ν`` when it was measured by the spread of repeated readings (with
  ``ν_noise`` degrees of freedom). With the noise estimated from the fit's own residuals
  ``χ² ≈ ν`` by construction: the test says nothing, and the p-value is None with the reason
  (:attr:`FitTest.untested_reason`), not a made-up number.
* the reduced chi-square of each channel, ``Σ r_c² / Σ (1 − h_c)`` (``h`` the leverages, the
  hat matrix's diagonal), so the channel that carries a misfit is named;
* outlier poses (static fits) or outlier time spans (moving fits, windows of
  :data:`SPAN_SECONDS`): a group's ``Σ r² / Σ (1 − h)`` tested against the noise, or against the
  scatter of the other groups when the noise came from the residuals or the fit fails (so one bad
  group cannot hide itself), at a family-wise rate of
  :data:`OUTLIER_ALPHA`;
* the condition number of the information ``JᵀJ`` in unit-diagonal scaling;
* the verdict: ``"fits"``, ``"does not fit"`` (``p <``
  :data:`FIT_ALPHA`) or ``"not tested"``, and for a misfit one
  warning that names the fit and the channel.

Each result exposes it as ``fit_test``; each calibration file writes it under the key
``fit_test`` (:meth:`FitTest.to_dict`).
"""

import logging
from dataclasses import dataclass, replace

import numpy as np

from ..exceptions import InvalidInput
from .covariance import RCOND
from .model import WRENCH_CHANNELS

__all__ = [
    "ACCEL_CHANNELS",
    "FIT_ALPHA",
    "OUTLIER_ALPHA",
    "SPAN_SECONDS",
    "WRENCH_CHANNELS",
    "FitTest",
    "fit_test",
]

logger = logging.getLogger(__name__)

FIT_ALPHA = 1e-3
"""p-value below which the chi-square test says the model does not fit."""

OUTLIER_ALPHA = 1e-3
"""Family-wise false-alarm rate of the outlier test (per pose or time span: ``OUTLIER_ALPHA / G``
for ``G`` of them)."""

ACCEL_CHANNELS = ("ax", "ay", "az")
"""The accelerometer's channels [m/s²]."""

SPAN_SECONDS = 1.0
"""Length [s] of the time windows a moving fit's outlier test judges."""

NOISE_SOURCES = ("given", "spread", "residuals")

VERDICTS = ("fits", "does not fit", "not tested")

RESIDUALS_REASON = (
    "the noise was estimated from this fit's own residuals, so the chi-square equals its degrees "
    "of freedom by construction and cannot test the model"
)
NOISE_ADVICE = "give the noise (noise=, --noise-force/--noise-torque) to have it tested"
"""How to have a fit tested whose noise came from its residuals (a moving recording's, which has
no repeated readings); the static fits add the spread of repeated readings."""
NO_DOF_REASON = "no degrees of freedom left: as many parameters as residuals"


def _f_sf(ratio, dfn, dfd):
    """Survival function of ``F(dfn, dfd)`` (vectorized); the chi-square's ``χ²(dfn)/dfn`` for an
    infinite ``dfd``."""
    from scipy import special  # here, not at import: scipy.special takes ~0.2 s to import

    ratio, dfn, dfd = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in (ratio, dfn, dfd)))
    large = ~np.isfinite(dfd) | (dfd > 1e7)
    with np.errstate(invalid="ignore"):
        chi_square = special.chdtrc(dfn, ratio * dfn)
        return np.where(large, chi_square, special.fdtrc(dfn, np.where(large, 1.0, dfd), ratio))


@dataclass(frozen=True)
class FitTest:
    """Whether a calibration's model fits its readings (all figures of the whitened residuals).

    Attributes:
        fit_name: The fit, as warnings name it (e.g. ``"the dynamic fit from joints"``).
        chi_square: ``χ² = Σ r²`` over all whitened residuals.
        dof: ``ν``: residuals minus the rank of the Jacobian (the parameters it determines).
        p_value: ``P(χ² ≥ observed)`` under the model (F test with a measured noise), or None
            when the test does not apply (:attr:`untested_reason`).
        untested_reason: Why there is no p-value, or None.
        noise_source: ``"given"``, ``"spread"`` (repeated readings) or ``"residuals"``.
        noise_dof: Degrees of freedom of the noise estimate (``inf`` when given).
        channel_names: The residuals' channels (``fx``..``mz``, after ``ax``..``az`` for the
            IMU's fits).
        channel_chi_square: Reduced chi-square per channel, ``Σ r_c² / Σ (1 − h_c)`` (about 1
            when the channel fits).
        outlier_kind: ``"poses"`` (static fits) or ``"time spans"`` (moving fits).
        outliers: Outlier pose ids, or outlier time spans ``(start, end)`` [s].
        condition_number: Of the information ``JᵀJ`` in unit-diagonal scaling (all fitted
            parameters).
        parameter_count: Parameters the fit estimated (the Jacobian's columns).
    """

    fit_name: str
    chi_square: float
    dof: int
    p_value: float | None
    untested_reason: str | None
    noise_source: str
    noise_dof: float
    channel_names: tuple[str, ...]
    channel_chi_square: np.ndarray
    outlier_kind: str
    outliers: tuple
    condition_number: float
    parameter_count: int

    def __post_init__(self):
        channels = np.array(self.channel_chi_square, dtype=float).reshape(-1)
        if len(channels) != len(self.channel_names):
            raise InvalidInput(
                f"{len(channels)} channel chi-squares for {len(self.channel_names)} channels "
                f"{list(self.channel_names)}"
            )
        if self.noise_source not in NOISE_SOURCES:
            raise InvalidInput(
                f"noise_source must be one of {NOISE_SOURCES}, got {self.noise_source}"
            )
        if self.outlier_kind not in ("poses", "time spans"):
            raise InvalidInput(
                f"outlier_kind must be 'poses' or 'time spans', got {self.outlier_kind}"
            )
        if (self.p_value is None) == (self.untested_reason is None):
            raise InvalidInput("a fit test has either a p_value or an untested_reason")
        channels.setflags(write=False)
        object.__setattr__(self, "channel_chi_square", channels)
        object.__setattr__(self, "channel_names", tuple(str(c) for c in self.channel_names))

    @property
    def verdict(self) -> str:
        """``"fits"``, ``"does not fit"`` (``p <`` :data:`FIT_ALPHA`) or ``"not tested"``."""
        if self.p_value is None:
            return "not tested"
        return "does not fit" if self.p_value < FIT_ALPHA else "fits"

    @property
    def fits(self) -> bool:
        """False only when the test rejects the model (True when not tested)."""
        return self.verdict != "does not fit"

    @property
    def covariance_scale(self) -> float:
        """``χ²/ν`` when the test rejects the model (and ``χ² > ν``), else 1: the factor a fit's
        covariance is scaled by (Birge ratio) so its standard errors stay honest."""
        return self.chi_square / self.dof if not self.fits and self.chi_square > self.dof else 1.0

    @property
    def worst_channel(self) -> tuple[str, float]:
        """``(name, share)``: the channel with the largest excess ``Σ r_c² − Σ (1 − h_c)`` and
        its share [0, 1] of all channels' excess (judged by the reduced chi-square)."""
        reduced = np.nan_to_num(self.channel_chi_square, nan=0.0)
        excess = np.maximum(reduced - 1.0, 0.0)
        worst = int(np.argmax(reduced))
        total = float(np.sum(excess))
        return self.channel_names[worst], (float(excess[worst]) / total if total > 0 else 0.0)

    @property
    def warning(self) -> str | None:
        """The misfit's warning naming the fit and the channel that carries it, or None."""
        if self.fits:
            return None
        name, share = self.worst_channel
        others = ", ".join(
            f"{channel} {value:.3g}"
            for channel, value in zip(self.channel_names, self.channel_chi_square)
        )
        text = (
            f"{self.fit_name} does not fit: chi² = {self.chi_square:.1f} for {self.dof} degrees "
            f"of freedom, p = {self.p_value:.1e}; channel {name} carries {100 * share:.0f} % of "
            f"the excess (reduced chi-square per channel: {others})"
        )
        if self.outliers:
            text += f"; outlier {self.outlier_kind}: {self._outlier_text()}"
        return text

    def _outlier_text(self) -> str:
        if self.outlier_kind == "poses":
            return ", ".join(str(i) for i in self.outliers)
        return ", ".join(f"{start:.3g}–{end:.3g} s" for start, end in self.outliers)

    def summary_line(self) -> str:
        """One line for a result's summary: chi-square, degrees of freedom, p and the verdict."""
        p_text = (
            "no p-value (noise from the residuals)"
            if self.p_value is None
            else (f"p = {self.p_value:.2g}")
        )
        return (
            f"  fit test        chi² {self.chi_square:.1f} for {self.dof} dof, {p_text}: "
            f"{self.verdict} (noise {self.noise_source})"
        )

    def to_dict(self) -> dict:
        """Plain-Python form, the calibration file's ``fit_test`` (non-finite numbers as null)."""
        outliers = (
            [int(i) for i in self.outliers]
            if self.outlier_kind == "poses"
            else [[float(start), float(end)] for start, end in self.outliers]
        )
        return {
            "fit_name": self.fit_name,
            "chi_square": _json_float(self.chi_square),
            "dof": int(self.dof),
            "p_value": None if self.p_value is None else float(self.p_value),
            "untested_reason": self.untested_reason,
            "verdict": self.verdict,
            "noise_source": self.noise_source,
            "noise_dof": _json_float(self.noise_dof),
            "channel_names": list(self.channel_names),
            "channel_chi_square": [_json_float(v) for v in self.channel_chi_square],
            "outlier_kind": self.outlier_kind,
            "outliers": outliers,
            "condition_number": _json_float(self.condition_number),
            "parameter_count": int(self.parameter_count),
        }

    @classmethod
    def from_dict(cls, data: dict) -> "FitTest":
        """Inverse of :meth:`to_dict` (``verdict`` must be the one ``p_value`` gives); raises
        KeyError/TypeError/ValueError on malformed input."""

        def number(key, missing=np.nan):
            return missing if data[key] is None else float(data[key])

        kind = str(data["outlier_kind"])
        p_value = None if data["p_value"] is None else float(data["p_value"])
        outliers = (
            tuple(int(i) for i in data["outliers"])
            if kind == "poses"
            else tuple((float(a), float(b)) for a, b in data["outliers"])
        )
        test = cls(
            fit_name=str(data["fit_name"]),
            chi_square=number("chi_square"),
            dof=int(data["dof"]),
            p_value=p_value,
            untested_reason=None
            if data["untested_reason"] is None
            else str(data["untested_reason"]),
            noise_source=str(data["noise_source"]),
            noise_dof=number("noise_dof", np.inf),
            channel_names=tuple(str(c) for c in data["channel_names"]),
            channel_chi_square=np.array(
                [np.nan if v is None else float(v) for v in data["channel_chi_square"]]
            ),
            outlier_kind=kind,
            outliers=outliers,
            condition_number=number("condition_number"),
            parameter_count=int(data["parameter_count"]),
        )
        if data["verdict"] != test.verdict:
            raise InvalidInput(
                f"verdict {data['verdict']!r} disagrees with p_value {p_value} (expected "
                f"{test.verdict!r}: 'does not fit' below {FIT_ALPHA:g})"
            )
        return test


FIT_TEST_TYPES = {
    "fit_name": "string",
    "chi_square": "number?",
    "dof": "integer",
    "p_value": "number?",
    "untested_reason": "string?",
    "verdict": "string",
    "noise_source": "string",
    "noise_dof": "number?",
    "channel_names": "strings",
    "channel_chi_square": "numbers?",
    "outlier_kind": "string",
    "condition_number": "number?",
    "parameter_count": "integer",
}
"""The JSON kind of each ``fit_test`` key (``JsonReader.check_types``)."""


def _json_float(value) -> float | None:
    return float(value) if np.isfinite(value) else None


def _leverage_and_spectrum(jacobian: np.ndarray) -> tuple[np.ndarray, int, float]:
    """``(leverages (rows,), rank, condition number)`` of a whitened Jacobian: the hat matrix's
    diagonal, the rank (eigenvalues of ``JᵀJ`` in unit-diagonal scaling above
    :data:`~ftkin.calibration.covariance.RCOND` of the largest, where rounding starts to decide),
    and its condition number. The leverages ``h_i = ‖J_i V Λ^(-1/2)‖²`` are summed in blocks of
    rows, so a long recording needs no second Jacobian-sized array."""
    norms = np.linalg.norm(jacobian, axis=0)
    scale = np.where(norms > 0.0, norms, 1.0)
    values, vectors = np.linalg.eigh((jacobian.T @ jacobian) / np.outer(scale, scale))
    kept = values > RCOND * values[-1]
    basis = vectors[:, kept] / scale[:, None] / np.sqrt(values[kept])
    blocks = np.array_split(jacobian, max(1, len(jacobian) // LEVERAGE_BLOCK_ROWS))
    leverage = np.concatenate([np.sum((block @ basis) ** 2, axis=1) for block in blocks])
    condition = float(values[-1] / values[0]) if values[0] > 0.0 else np.inf
    return leverage, int(np.sum(kept)), condition


LEVERAGE_BLOCK_ROWS = 100_000
"""Rows of the Jacobian per block when its leverages are summed."""


def _groups(rows: int, group_ids, times) -> tuple[np.ndarray, list, str]:
    """``(group index per row, labels, kind)``: poses by ``group_ids``, windows of
    :data:`SPAN_SECONDS` over ``times``, or one group per row."""
    if times is not None:
        times = np.asarray(times, dtype=float).reshape(-1)
        index = np.floor((times - times.min()) / SPAN_SECONDS).astype(int)
        _, index = np.unique(index, return_inverse=True)
        labels = [
            (float(times[index == k].min()), float(times[index == k].max()))
            for k in range(index.max() + 1)
        ]
        return index, labels, "time spans"
    ids = np.arange(rows) if group_ids is None else np.asarray(group_ids).reshape(-1)
    labels, index = np.unique(ids, return_inverse=True)
    return index, [int(v) for v in labels], "poses"


def fit_test(
    fit_name: str,
    whitened,
    jacobian=None,
    *,
    channel_names,
    noise_source: str,
    noise_dof: float = np.inf,
    group_ids=None,
    times=None,
    leverage=None,
    information=None,
    parameter_count: int | None = None,
    log: bool = True,
    noise_advice: str = NOISE_ADVICE,
) -> FitTest:
    """The goodness of fit of a calibration (module docstring): the one computation every kind
    runs.

    Args:
        fit_name: How warnings name the fit (``"the static fit from joints"``).
        whitened: ``(rows, C)`` whitened residuals ``(measured − predicted) / σ`` (a pose mean's
            ``σ`` over the square root of its readings), one column per channel.
        jacobian: ``(rows · C, n)`` whitened Jacobian, rows in ``whitened.ravel()``'s order; or
            None with ``leverage`` and ``information`` (a fit that keeps them).
        channel_names: The ``C`` channels' names.
        noise_source: ``"given"``, ``"spread"`` or ``"residuals"`` (then no p-value).
        noise_dof: Degrees of freedom of a noise measured by the spread (``inf`` when given).
        group_ids: ``(rows,)`` the pose of each row (static fits; default: each row its own).
        times: ``(rows,)`` time of each row [s] (moving fits: outliers are time spans).
        leverage: ``(rows, C)`` the hat matrix's diagonal, instead of ``jacobian``.
        information: ``(n, n)`` the information ``JᵀJ``, instead of ``jacobian``.
        parameter_count: Parameters fitted (default: the Jacobian's rank).
        log: False keeps a misfit's warning out of the log (the caller logs it).
        noise_advice: What to do to have the fit tested when the noise came from its residuals
            (it ends :attr:`FitTest.untested_reason`; the fit's own keywords and flags).

    Returns:
        A frozen :class:`FitTest`; a misfit's :attr:`FitTest.warning` is logged to
        ``ftkin.calibration.goodness_of_fit`` when ``log``.
    """
    whitened = np.asarray(whitened, dtype=float)
    if whitened.ndim != 2 or whitened.shape[1] != len(channel_names):
        raise InvalidInput(
            f"whitened must be (rows, {len(channel_names)}) for channels {list(channel_names)}, "
            f"got shape {whitened.shape}"
        )
    if jacobian is not None:
        jacobian = np.asarray(jacobian, dtype=float)
        flat, rank, condition = _leverage_and_spectrum(jacobian)
        leverage, count = flat.reshape(whitened.shape), jacobian.shape[1]
    else:
        information = np.asarray(information, dtype=float)
        diagonal = np.sqrt(np.maximum(np.diag(information), 1e-300))
        eigenvalues = np.linalg.eigvalsh(information / np.outer(diagonal, diagonal))
        condition = float(eigenvalues[-1] / eigenvalues[0]) if eigenvalues[0] > 0 else np.inf
        leverage = np.asarray(leverage, dtype=float).reshape(whitened.shape)
        rank = count = len(information)
    if parameter_count is not None:
        parameter_count = count = int(parameter_count)
    else:
        parameter_count = rank
    chi_square = float(np.sum(whitened**2))
    dof = int(whitened.size - parameter_count)
    reason = f"{RESIDUALS_REASON}; {noise_advice}" if noise_source == "residuals" else None
    reason = reason or (NO_DOF_REASON if dof <= 0 else None)
    p_value = None if reason else float(_f_sf(chi_square / dof, dof, noise_dof))
    free = np.clip(1.0 - leverage, 0.0, 1.0)
    with np.errstate(invalid="ignore", divide="ignore"):
        channel = np.sum(whitened**2, axis=0) / np.sum(free, axis=0)
    index, labels, kind = _groups(len(whitened), group_ids, times)
    misfit = p_value is not None and p_value < FIT_ALPHA
    test = FitTest(
        fit_name=fit_name,
        chi_square=chi_square,
        dof=dof,
        p_value=p_value,
        untested_reason=reason,
        noise_source=noise_source,
        noise_dof=float(noise_dof),
        channel_names=tuple(channel_names),
        channel_chi_square=channel,
        outlier_kind=kind,
        outliers=(),
        condition_number=condition,
        parameter_count=count,
    )
    if dof > 0:
        group_p = _group_p_values(
            whitened, free, index, len(labels), noise_source, noise_dof, misfit, chi_square, dof
        )
        flagged = np.flatnonzero(group_p < OUTLIER_ALPHA / max(len(labels), 1))
        test = replace(test, outliers=_merged([labels[k] for k in flagged], kind))
    if log and test.warning is not None:
        logger.warning("%s", test.warning)
    return test


def _group_p_values(whitened, free, index, count, source, noise_dof, misfit, chi_square, dof):
    """``(G,)`` p-value of each group's ``Σ r² / Σ (1 − h)``: against the noise, or against the
    other groups' scatter when the noise came from the residuals or the fit fails (NaN when there
    is no scatter to judge by)."""
    z = np.bincount(index, weights=np.sum(whitened**2, axis=1), minlength=count)
    nu = np.maximum(np.bincount(index, weights=np.sum(free, axis=1), minlength=count), 1e-12)
    scale, denominator = np.ones(count), np.full(count, float(noise_dof))
    if source == "residuals" or misfit:
        denominator = dof - nu
        with np.errstate(invalid="ignore", divide="ignore"):
            scale = (chi_square - z) / denominator
        if source != "residuals":
            scale = np.maximum(scale, 1.0)
        scale = np.where((denominator > 0) & (scale > 0), scale, np.nan)
    ratio = z / nu / scale
    valid = np.isfinite(ratio)
    return np.where(
        valid,
        _f_sf(
            np.where(valid, ratio, 0.0),
            nu,
            np.where(valid & (denominator > 0), denominator, np.inf),
        ),
        np.nan,
    )


def _merged(labels: list, kind: str) -> tuple:
    """Outlier labels; adjacent time windows merged into one span."""
    if kind == "poses" or not labels:
        return tuple(labels)
    spans = [list(labels[0])]
    for start, end in labels[1:]:
        if start - spans[-1][1] <= SPAN_SECONDS:
            spans[-1][1] = end
        else:
            spans.append([start, end])
    return tuple((start, end) for start, end in spans)
