"""A one-page calibration report as a figure (optional extra ``plots``: matplotlib).

Like the paper's Fig. 5: for each channel ``fx..mz`` the per-pose mean of the
measured raw readings (with the standard error of that mean as error bars,
when a pose has several readings) against the calibrated model's prediction,
and below it the residual (measured − predicted) per pose. A text panel gives
the parameters with their standard errors when the calibration has a
covariance. When the calibration carries time series (a drifting sensor's
bias trajectory, the residual during motion: :mod:`ftkin.viz.report_series`),
a row of panels per series follows. Drawn with the non-interactive Agg backend
(no display needed).
"""

import io
from pathlib import Path

import numpy as np

from ..calibration.conventions import as_real_sensor
from ..calibration.model import WRENCH_CHANNELS, SensorModel
from ..calibration.result import CalibrationResult
from ..calibration.samples import Samples
from ..calibration.samples_arm import warn_if_samples_arm_differs
from ..control.bias_checks import bias_at_times
from ..exceptions import InvalidInput, MissingDependency
from ..io.atomic import atomic_write_bytes
from .report_series import draw_series, report_series

_UNITS = ("N", "N", "N", "N·m", "N·m", "N·m")


SUMMARY_FONT_SIZE = 8
"""Font size of the summary text [pt]."""
SUMMARY_WIDTH = 180
"""Characters per summary line on the 14-inch page (monospace at :data:`SUMMARY_FONT_SIZE`); longer
lines wrap.
"""


def _wrapped(text: str) -> str:
    """``text`` with lines longer than :data:`SUMMARY_WIDTH` wrapped, continuation lines
    indented.
    """
    import textwrap

    lines = []
    for line in text.splitlines():
        indent = " " * (len(line) - len(line.lstrip()) + 4)
        lines.extend(
            textwrap.wrap(
                line,
                SUMMARY_WIDTH,
                subsequent_indent=indent,
                drop_whitespace=False,
                break_on_hyphens=False,
            )
            or [""]
        )
    return "\n".join(lines)


def new_figure(figsize: tuple[float, float], purpose: str):
    """A matplotlib ``Figure`` of ``figsize`` [in] on the Agg canvas (no display, not attached to
    pyplot; constrained layout), or :class:`MissingDependency` (extra ``plots``) naming
    ``purpose``.
    """
    try:
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure
    except ImportError:
        raise MissingDependency("matplotlib", "plots", purpose) from None
    figure = Figure(figsize=figsize, layout="constrained")
    FigureCanvasAgg(figure)
    return figure


def save_figure(figure, path, fmt: str, dpi: int) -> Path:
    """Write ``figure`` to ``path`` in the format ``fmt`` atomically; returns the path."""
    buffer = io.BytesIO()
    figure.savefig(buffer, format=fmt, dpi=dpi)
    return atomic_write_bytes(path, buffer.getvalue())


def _as_calibration(calibration) -> CalibrationResult:
    if not isinstance(calibration, SensorModel):
        raise InvalidInput(
            "calibration must be an ftkin SensorModel or CalibrationResult, got "
            f"{type(calibration).__name__}"
        )
    return CalibrationResult.from_model(calibration)


def report_data(calibration, samples: Samples) -> dict[str, np.ndarray]:
    """Per-pose arrays the report plots.

    Returns a dict with ``pose_ids`` ``(P,)``, ``measured`` ``(P, 6)`` (mean raw
    wrench [N, N·m]), ``predicted`` ``(P, 6)`` (model prediction at the pose's
    mean orientation; for a drift-aware calibration and samples with times,
    with the bias at the pose's time, :func:`~ftkin.control.bias_checks.bias_at_times`),
    ``residuals`` = measured − predicted, and
    ``standard_error`` ``(P, 6)`` (spread / √count; NaN for single readings).
    """
    calibration = _as_calibration(calibration)
    if not isinstance(samples, Samples):
        raise InvalidInput(f"samples must be an ftkin.Samples, got {type(samples).__name__}")
    poses = as_real_sensor(
        samples, calibration
    ).pose_averages()  # the stored sign, axis flip and mount applied
    warn_if_samples_arm_differs(samples, calibration)
    predicted = calibration.predict(poses.rotations)
    if poses.times is not None and calibration.drift is not None:
        # the bias a reading at that time had, by compensate's rule (the trajectory inside the
        # recording, the calibration's bias, re-zeroed perhaps, elsewhere)
        predicted = calibration.tool_gravity_wrench(poses.rotations) + bias_at_times(
            calibration.drift, calibration.bias, poses.times
        )
    return {
        "pose_ids": poses.pose_ids,
        "measured": poses.wrenches,
        "predicted": predicted,
        "residuals": poses.wrenches - predicted,
        "standard_error": poses.spread / np.sqrt(poses.counts)[:, None],
    }


def report_figure(calibration, samples: Samples, title: str | None = None, series=()):
    """A matplotlib ``Figure`` (not attached to pyplot) with the report.

    ``series``: more time series to plot (:class:`~ftkin.viz.report_series.Series`, e.g. the
    residual during motion) after the calibration's own bias trajectory.

    Raises:
        MissingDependency: matplotlib is not installed (extra ``plots``).
    """
    data = report_data(calibration, samples)
    summary = (
        calibration.summary() if isinstance(calibration, CalibrationResult) else repr(calibration)
    )
    calibration = _as_calibration(calibration)
    series = report_series(calibration, series)
    if calibration.std_errors is None:
        summary += "\n  (no standard errors: the calibration has no covariance)"
    summary = _wrapped(summary)
    text_height = 0.2 + len(summary.splitlines()) * SUMMARY_FONT_SIZE * 1.25 / 72.0  # [in]
    heights = [2.6, 1.2, 2.6, 1.2, text_height] + [2.3] * len(series)  # [in]
    figure = new_figure((14, sum(heights) + 0.6), "plotting a calibration report")
    grid = figure.add_gridspec(5 + len(series), 3, height_ratios=heights)
    x = np.arange(len(data["pose_ids"]))
    error = np.nan_to_num(data["standard_error"], nan=0.0)
    for channel, (name, unit) in enumerate(zip(WRENCH_CHANNELS, _UNITS)):
        row, column = 2 * (channel // 3), channel % 3
        top = figure.add_subplot(grid[row, column])
        top.errorbar(
            x, data["measured"][:, channel], yerr=error[:, channel], fmt="o", ms=3, label="measured"
        )
        top.plot(x, data["predicted"][:, channel], "-", lw=1, label="predicted")
        top.set(ylabel=f"{name} [{unit}]", title=name)
        top.tick_params(labelbottom=False)
        if channel == 0:
            top.legend(loc="best", fontsize="small")
        bottom = figure.add_subplot(grid[row + 1, column], sharex=top)
        bottom.axhline(0.0, color="0.5", lw=0.8)
        bottom.errorbar(
            x, data["residuals"][:, channel], yerr=error[:, channel], fmt=".", ms=3, color="C3"
        )
        bottom.set(ylabel=f"residual [{unit}]", xlabel="pose")
    text = figure.add_subplot(grid[4, :])
    text.axis("off")
    text.text(
        0.0,
        1.0,
        summary,
        family="monospace",
        fontsize=SUMMARY_FONT_SIZE,
        va="top",
        ha="left",
        transform=text.transAxes,
    )
    for k, one in enumerate(series):
        draw_series(figure, grid[5 + k, :].subgridspec(1, 4), one)
    figure.suptitle(title or f"ftkin calibration report: {len(x)} poses, {len(samples)} readings")
    return figure


def save_report(
    calibration, samples: Samples, path, title: str | None = None, dpi: int = 100, series=()
) -> Path:
    """Draw :func:`report_figure` and write it (format from the suffix: .png, .pdf, .svg)
    atomically.
    """
    path = Path(path)
    fmt = path.suffix.lstrip(".").lower() or "png"
    if fmt not in ("png", "pdf", "svg"):
        raise InvalidInput(f"report file must end in .png, .pdf or .svg, got {path.name!r}")
    return save_figure(report_figure(calibration, samples, title, series), path, fmt, dpi)
