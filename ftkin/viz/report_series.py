"""Optional time-series panels of the calibration report.

Quantities that vary over time: the bias trajectory of a drifting sensor (a
calibration's declared ``drift``, :class:`~ftkin.calibration.drift.BiasDrift`)
and any series the caller adds (e.g. the residual during motion).
:func:`report_series` lists them and :func:`draw_series` plots each as a row of
two panels (forces [N], torques [N·m]) against time [s]. An added series
(:func:`as_series`) is any of:

* a pair ``(times, values)``;
* a mapping with ``"times"`` and ``"values"`` (or the attribute's own kind:
  ``"bias"``, ``"residual"``, ``"residuals"``);
* an object with such attributes.

``times`` is ``(N,)`` [s], ``values`` ``(N, 6)`` ``[fx, fy, fz, mx, my, mz]``
[N, N·m], sensor frame.
"""

from dataclasses import dataclass

import numpy as np

from ..calibration.model import WRENCH_CHANNELS
from ..exceptions import InvalidInput

DRIFT_TITLE = "bias of a drifting sensor"
_VALUE_KEYS = ("values", "bias", "residual", "residuals")


@dataclass(frozen=True)
class Series:
    """One time series to plot.

    Attributes:
        name: The calibration attribute it came from.
        title: Panel title.
        times: ``(N,)`` times [s].
        values: ``(N, 6)`` wrench channels [N, N·m].
    """

    name: str
    title: str
    times: np.ndarray
    values: np.ndarray


def _field(source, key):
    if isinstance(source, dict):
        return source.get(key)
    return getattr(source, key, None)


def as_series(name: str, title: str, source) -> Series:
    """Read one series (see the module docstring for the accepted forms).

    Raises:
        InvalidInput: the shapes do not match ``(N,)`` and ``(N, 6)`` or are not finite.
    """
    if isinstance(source, (tuple, list)) and len(source) == 2:
        times, values = source
    else:
        times = _field(source, "times")
        values = next(
            (v for v in (_field(source, key) for key in _VALUE_KEYS) if v is not None), None
        )
    try:
        times = np.asarray(times, dtype=float).reshape(-1)
        values = np.asarray(values, dtype=float)
    except (TypeError, ValueError):
        raise InvalidInput(f"{name}: expected times (N,) [s] and values (N, 6) [N, N·m]") from None
    if values.ndim != 2 or values.shape != (len(times), 6) or len(times) == 0:
        raise InvalidInput(
            f"{name}: expected times (N,) [s] and values (N, 6) [N, N·m], got {times.shape} and "
            f"{values.shape}"
        )
    if not (np.all(np.isfinite(times)) and np.all(np.isfinite(values))):
        raise InvalidInput(f"{name}: times and values must be finite")
    return Series(name, title, times, values)


def report_series(calibration, extra=()) -> list[Series]:
    """The calibration's bias trajectory (unless constant), then the ``extra`` series."""
    drift = calibration.drift
    own = (
        []
        if drift is None or drift.model == "none"
        else [Series("drift", DRIFT_TITLE, drift.times, drift.bias)]
    )
    return own + list(extra)


def draw_series(figure, grid_row, series: Series) -> list:
    """Plot ``series`` into the two halves of ``grid_row`` (a gridspec row); returns the two
    axes.
    """
    axes = [figure.add_subplot(grid_row[0, :2]), figure.add_subplot(grid_row[0, 2:])]
    for first, ax, quantity, unit in zip((0, 3), axes, ("force", "torque"), ("N", "N·m")):
        for channel in range(first, first + 3):
            ax.plot(series.times, series.values[:, channel], lw=1, label=WRENCH_CHANNELS[channel])
        ax.set(
            xlabel="time [s]", ylabel=f"{quantity} [{unit}]", title=f"{series.title}: {quantity}s"
        )
        ax.legend(loc="best", fontsize="small")
    return axes
