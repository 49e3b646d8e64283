"""Every pose of a calibration in one image: the contact sheet of ``ftkin view --png``.

Each pose is drawn by a :class:`~ftkin.viz.viewer.CalibrationViewer` (camera
framed on the sensor, :mod:`ftkin.viz.framing`), saved as a static page and
screenshotted by headless Chromium; the screenshots run :data:`WORKERS` at a
time (each is a separate Chromium process, so threads suffice). matplotlib
tiles them in a grid, each cell titled with its label and the angle between
the measured force (minus bias) and the predicted tool gravity; outlier poses
get a red frame.
"""

import math
import tempfile
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..exceptions import InvalidInput, MissingDependency
from .browser import screenshot_html
from .legend import ARROWS, CENTER_OF_MASS, add_legend
from .report import new_figure, save_figure

WORKERS = 2
"""Chromium screenshots run at the same time."""

CELL_SIZE = (512, 384)
"""Screenshot size of one cell ``(width, height)`` [px]."""


HIDE_CONTROLS = "<style>.dg{display:none !important}</style>"
"""CSS that hides meshcat's "Open Controls" bar in a cell."""

_PURPOSE = "the contact sheet of ftkin view --png"  # what matplotlib is needed for


@dataclass(frozen=True)
class SheetCell:
    """One pose on the sheet.

    Attributes:
        label: Title of the cell (e.g. ``pose 3``).
        angle_deg: Angle between ``R_BS (F - F0)`` and the predicted gravity [deg].
        outlier: Whether the cell gets a red frame.
        page: The static HTML page of the pose.
    """

    label: str
    angle_deg: float
    outlier: bool
    page: str


def force_angle_deg(a, b) -> float:
    """Angle between two 3-vectors [deg]; NaN when one is zero."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    na, nb = np.linalg.norm(a), np.linalg.norm(b)
    if na == 0.0 or nb == 0.0:
        return math.nan
    return math.degrees(math.atan2(float(np.linalg.norm(np.cross(a, b))), float(a @ b)))


def sheet_cells(
    viewer, labels: Sequence[str], raw_wrenches, *, configurations=None, rotations=None, outliers=()
) -> list[SheetCell]:
    """Draw each pose in ``viewer`` and keep its static page (no legend: the sheet has one).

    Args:
        viewer: A :class:`~ftkin.viz.viewer.CalibrationViewer`.
        labels: One title per pose.
        raw_wrenches: ``(N, 6)`` raw readings [N, N·m].
        configurations: ``(N, nq)`` joint angles [rad], or
        rotations: ``(N, 3, 3)`` ``R_BS`` (no arm).
        outliers: Indices (into ``labels``) of poses to outline in red.
    """
    raw = np.asarray(raw_wrenches, dtype=float)
    if len(labels) != len(raw) or len(raw) == 0:
        raise InvalidInput(
            f"contact sheet: {len(labels)} labels for {len(raw)} readings; expected the same "
            "non-zero count"
        )
    outliers, cells = set(outliers), []
    for k, label in enumerate(labels):
        vectors = (
            viewer.show_pose(configurations[k], raw[k])
            if configurations is not None
            else viewer.show_rotation(rotations[k], raw[k])
        )
        angle = force_angle_deg(vectors.measured_force, vectors.gravity_force)
        page = add_legend(viewer.static_html(legend=False), HIDE_CONTROLS)
        cells.append(SheetCell(label, angle, k in outliers, page))
    return cells


def render_cells(
    cells: Sequence[SheetCell], size=CELL_SIZE, workers: int = WORKERS, timeout: float = 180.0
) -> list[np.ndarray]:
    """Screenshot every cell's page (``timeout`` [s] each); returns ``(H, W, 3)`` uint8 images in
    order.
    """
    try:  # before the screenshots: matplotlib reads them
        from matplotlib.image import imread
    except ImportError:
        raise MissingDependency("matplotlib", "plots", _PURPOSE) from None
    with tempfile.TemporaryDirectory(prefix="ftkin-sheet-") as scratch:

        def shoot(k: int) -> np.ndarray:
            png = screenshot_html(
                cells[k].page, Path(scratch) / f"cell{k}.png", window_size=size, timeout=timeout
            )
            return np.round(imread(str(png))[..., :3] * 255).astype(np.uint8)  # PNG: floats 0–1

        with ThreadPoolExecutor(max_workers=max(int(workers), 1)) as pool:
            return list(pool.map(shoot, range(len(cells))))


def sheet_figure(
    cells: Sequence[SheetCell],
    images: Sequence[np.ndarray],
    title: str = "",
    columns: int | None = None,
):
    """A matplotlib ``Figure`` (not attached to pyplot) tiling ``images`` with labels and red
    outlier frames.
    """
    count = len(cells)
    columns = columns or math.ceil(math.sqrt(count))
    rows = math.ceil(count / columns)
    height, width = images[0].shape[:2]
    figure = new_figure((3.2 * columns, 3.2 * rows * height / width + 0.9), _PURPOSE)  # [in]
    axes = figure.subplots(rows, columns, squeeze=False).ravel()
    for ax in axes[count:]:
        ax.axis("off")
    for ax, cell, image in zip(axes, cells, images):
        ax.imshow(image)
        ax.set(xticks=[], yticks=[])
        angle = "n/a" if math.isnan(cell.angle_deg) else f"{cell.angle_deg:.2f}°"
        ax.set_title(
            f"{cell.label}: angle {angle}" + (" (outlier)" if cell.outlier else ""),
            fontsize=9,
            color="red" if cell.outlier else "black",
        )
        for spine in ax.spines.values():
            spine.set(
                edgecolor="red" if cell.outlier else "0.6", linewidth=4.0 if cell.outlier else 0.8
            )
    key = ", ".join(
        f"{name} = {layer.label}" for name, layer in zip(("magenta", "cyan", "yellow"), ARROWS)
    )
    key += f"\ngreen dot = {CENTER_OF_MASS.label}, purple = estimated gravity direction of the base"
    figure.suptitle(
        (title + "\n" if title else "")
        + "angle: between the measured force − bias and the predicted gravity",
        fontsize=10,
    )
    figure.supxlabel(key, fontsize=7)
    return figure


def save_contact_sheet(
    cells: Sequence[SheetCell],
    path,
    *,
    title: str = "",
    size=CELL_SIZE,
    workers: int = WORKERS,
    dpi: int = 110,
) -> Path:
    """Render the cells and write the sheet to ``path`` (.png) atomically; returns the path."""
    path = Path(path)
    if path.suffix.lower() != ".png":
        raise InvalidInput(f"contact sheet file must end in .png, got {path.name!r}")
    images = render_cells(cells, size, workers)
    return save_figure(sheet_figure(cells, images, title), path, "png", dpi)
