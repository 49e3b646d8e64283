"""Joint velocities and accelerations from sampled joint positions (Savitzky–Golay).

Offline (:func:`joint_derivatives`): a zero-phase Savitzky–Golay filter
(``scipy.signal.savgol_filter``) fits a polynomial of degree ``polyorder`` to a
centred window of ``window`` samples and differentiates it: no delay, and the
noise of ``q`` is smoothed before it is differentiated twice.

Online (:class:`CausalDifferentiator`): the same polynomial fit over the last
``window`` samples only, evaluated at the window's centre. Its output is
therefore the zero-phase estimate for the sample ``(window − 1) / 2`` ticks ago:
a known, constant delay of ``(window − 1) / 2 · dt`` seconds (:attr:`delay`).
Evaluating at the newest sample instead would remove the delay at the price of
much larger noise (the fit's edge), which is why ftkin does not.
"""

from collections import deque

import numpy as np

from ..exceptions import InvalidInput
from ..validation import as_batch, as_positive

DEFAULT_WINDOW_SECONDS = 0.051
"""Default Savitzky–Golay window [s] (51 samples at 1 kHz)."""

DEFAULT_POLYORDER = 4
"""Default Savitzky–Golay polynomial degree."""


def window_samples(
    sample_period: float,
    window_seconds: float = DEFAULT_WINDOW_SECONDS,
    polyorder: int = DEFAULT_POLYORDER,
) -> int:
    """Odd window length [samples] covering about ``window_seconds`` [s], larger than
    ``polyorder``.
    """
    count = max(
        round(
            as_positive(window_seconds, "window_seconds")
            / as_positive(sample_period, "sample_period")
        ),
        polyorder + 2,
    )
    return count if count % 2 == 1 else count + 1


MAX_MOTION_PERIOD = 0.1
"""Longest sample period [s] of a moving recording: below 10 Hz the accelerations of any useful
motion are lost.
"""


def uniform_period(times) -> float:
    """The sample period [s] of uniformly sampled stamps ``(N,)``.

    Raises:
        InvalidInput: fewer than two stamps, not increasing, or jitter above 5 % of the period
            (resample the log first: Savitzky–Golay assumes a uniform grid).
    """
    times = np.asarray(times, dtype=float)
    if times.ndim != 1 or len(times) < 2 or not np.all(np.isfinite(times)):
        raise InvalidInput(
            f"times must be a finite 1-D array of at least two stamps, got shape {times.shape}"
        )
    steps = np.diff(times)
    period = float(np.median(steps))
    if period <= 0.0 or np.any(steps <= 0.0):
        raise InvalidInput("times must increase strictly")
    if np.max(np.abs(steps - period)) > 0.05 * period:
        raise InvalidInput(
            f"times are not uniformly sampled (period {period:g} s, steps from {steps.min():g} to "
            f"{steps.max():g} s); "
            "resample the recording to a uniform rate first"
        )
    return period


def joint_derivatives(
    times, joint_positions, window: int | None = None, polyorder: int = DEFAULT_POLYORDER
):
    """Zero-phase smoothed ``q``, ``dq`` [rad/s] and ``ddq`` [rad/s²] of a uniformly sampled ``(N,
    nq)`` trajectory.

    Args:
        times: ``(N,)`` stamps [s] (uniform).
        joint_positions: ``(N, nq)`` [rad].
        window: Odd window length [samples]; default :func:`window_samples` of the period.
        polyorder: Polynomial degree (≥ 2 for accelerations).

    Returns:
        ``(q, dq, ddq)``, each ``(N, nq)``.
    """
    from scipy.signal import savgol_filter

    period = uniform_period(times)
    if period > MAX_MOTION_PERIOD:
        raise InvalidInput(
            f"the stamps are {period:g} s apart: a moving recording for accelerations needs at "
            "least "
            f"{1.0 / MAX_MOTION_PERIOD:g} Hz; t must be in seconds (stamps in milliseconds? divide "
            "by 1000)"
        )
    q, _ = as_batch(joint_positions, np.shape(joint_positions)[-1], "joint positions q")
    window = window_samples(period, polyorder=polyorder) if window is None else int(window)
    _check_window(window, polyorder, len(q))
    return tuple(
        savgol_filter(q, window, polyorder, deriv=k, delta=period, axis=0, mode="interp")
        for k in range(3)
    )


def _check_window(window: int, polyorder: int, count: int | None = None) -> None:
    if polyorder < 2:
        raise InvalidInput(f"polyorder must be at least 2 to give accelerations, got {polyorder}")
    if window % 2 == 0 or window <= polyorder:
        raise InvalidInput(
            f"window must be odd and larger than polyorder {polyorder}, got {window}"
        )
    if count is not None and count < window:
        raise InvalidInput(f"{count} samples are fewer than the differentiation window of {window}")


class CausalDifferentiator:
    """Online ``q, dq, ddq`` from a stream of joint positions, with a fixed delay.

    Args:
        nq: Number of joints.
        sample_period: Control period [s].
        window: Odd window length [samples] (default :func:`window_samples`).
        polyorder: Polynomial degree (≥ 2).

    Each :meth:`update` returns the estimate at the centre of the last
    ``window`` samples, i.e. for the time ``delay`` seconds ago; None until
    the window is full.
    """

    def __init__(
        self,
        nq: int,
        sample_period: float,
        window: int | None = None,
        polyorder: int = DEFAULT_POLYORDER,
    ):
        from scipy.signal import savgol_coeffs

        period = as_positive(sample_period, "sample_period")
        window = window_samples(period, polyorder=polyorder) if window is None else int(window)
        _check_window(window, polyorder)
        self.nq = int(nq)
        self.window = window
        self.sample_period = period
        # savgol_coeffs(use="dot") weights the window oldest → newest, evaluated at its centre.
        self._weights = np.stack(
            [savgol_coeffs(window, polyorder, deriv=k, delta=period, use="dot") for k in range(3)]
        )
        self._buffer: deque = deque(maxlen=window)

    @property
    def delay(self) -> float:
        """Delay of the estimates [s]: ``(window − 1) / 2 · sample_period``."""
        return (self.window - 1) / 2 * self.sample_period

    def reset(self) -> None:
        """Forget the stream (after a pause or a jump in ``q``)."""
        self._buffer.clear()

    def update(self, q) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        """Push one ``(nq,)`` joint position [rad]; ``(q, dq, ddq)`` of ``delay`` s ago, or None
        while filling.
        """
        q = np.asarray(q, dtype=float)
        if q.shape != (self.nq,) or not np.all(np.isfinite(q)):
            raise InvalidInput(f"q must be a finite ({self.nq},) array, got {q!r}")
        self._buffer.append(q)
        if len(self._buffer) < self.window:
            return None
        estimate = self._weights @ np.asarray(self._buffer)
        return estimate[0], estimate[1], estimate[2]
