"""Figures of the placement experiment, like the paper's Fig. 6 and Fig. 7.

* :func:`plot_runs`: displacement [mm], velocity [mm/s] and force ``F'z`` [N]
  against time for one or more runs (Fig. 6: position control on the sponge
  and the book; Fig. 7: admittance with and without compensation).
* :func:`plot_sweep`: the same panels for a gain sweep, one line per gain.

matplotlib is optional (extra ``plots``); it is imported here, lazily, with
the non-interactive Agg backend.
"""

import io
from collections.abc import Sequence
from pathlib import Path

from ..exceptions import MissingDependency
from ..io.atomic import atomic_write_bytes
from .placement import PLACED_FORCE, PlacementRun


def _pyplot():
    try:
        import matplotlib
    except ImportError:
        raise MissingDependency(
            "matplotlib", "plots", "plotting the placement experiment"
        ) from None
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def run_label(run: PlacementRun) -> str:
    """``"sponge, admittance (k13 0.1 mm/N, k23 1 mm/(s·N))"``."""
    scenario = run.scenario
    label = f"{scenario.surface.name}, {scenario.mode}"
    if scenario.mode != "position":
        label += f" (k13 {scenario.k1 * 1e3:g} mm/N, k23 {scenario.k2 * 1e3:g} mm/(s·N))"
    return label


def plot_runs(
    runs: Sequence[PlacementRun],
    path,
    title: str | None = None,
    labels: Sequence[str] | None = None,
) -> Path:
    """Write a PNG with displacement, velocity and force of each run against time."""
    plt = _pyplot()
    labels = list(labels) if labels is not None else [run_label(run) for run in runs]
    figure, axes = plt.subplots(3, 1, sharex=True, figsize=(8, 8))
    for run, label in zip(runs, labels):
        style = {"label": label, "linestyle": "--" if run.scenario.mode == "position" else "-"}
        for axis, values in zip(axes, (run.displacement * 1e3, run.mean_speed() * 1e3, run.force)):
            axis.plot(run.time, values, **style)
    for axis, label in zip(
        axes,
        (
            "tool z displacement [mm]",
            "tool z velocity [mm/s]\n(0.1 s mean)",
            "F'z (sensor z, down) [N]",
        ),
    ):
        axis.set_ylabel(label)
        axis.grid(True, alpha=0.3)
    for level in (-PLACED_FORCE, PLACED_FORCE):
        axes[2].axhline(level, color="grey", linewidth=0.6, linestyle=":")
    axes[2].set_xlabel("time [s]")
    axes[0].legend(fontsize=8)
    if title:
        figure.suptitle(title)
    figure.tight_layout()
    buffer = io.BytesIO()
    figure.savefig(buffer, format="png", dpi=110)
    plt.close(figure)
    return atomic_write_bytes(path, buffer.getvalue())


def plot_sweep(runs: Sequence[PlacementRun], gain: str, path, title: str | None = None) -> Path:
    """Write a PNG of a gain sweep (``gain`` is ``"k1"`` or ``"k2"``), with each run's settle
    time.
    """
    name, unit = ("k13", "mm/N") if gain == "k1" else ("k23", "mm/(s·N)")
    labels = [
        f"{name} = {getattr(run.scenario, gain) * 1e3:g} {unit}: "
        + (f"placed at {run.settle_time:.2f} s" if run.placed else "not placed")
        for run in runs
    ]
    return plot_runs(runs, path, title, labels)
