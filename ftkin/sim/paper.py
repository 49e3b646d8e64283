"""The paper's own data and printed results (METHOD.md §6), for reproduction.

``paper_samples()`` loads Table 1 (commanded Euler angles α, β, γ [deg]) and
Table 2 (mean readings of 500 per pose); ``PAPER_RESULTS`` holds the values the
paper printed, with the digits it printed them to.
"""

from __future__ import annotations

from importlib import resources

import numpy as np

from ..calibration.estimate import CalibrationResult, calibrate
from ..calibration.samples import Samples
from ..io.samples_csv import load_samples

PAPER_G = 9.8
"""Gravity the paper used to turn weights into masses [m/s²]."""

PAPER_RESULTS = {
    "base_tilt_deg": (-0.204, -0.129),
    "tool_weight": 3.153,
    "force_offset": (-0.8613, 1.1015, 0.1976),
    "torque_offset": (-0.0002, -0.0605, 0.0254),
    "center_of_mass": (0.0001, -0.0003, 0.0470),
    "mean_relative_error_pct": (1.99, 2.98, 0.27, 3.87, 3.34, 0.71),
}
"""Printed results (torque_offset z and the error row as re-run, see METHOD.md)."""

PRINTED_DECIMALS = {
    "base_tilt_deg": 3,
    "tool_weight": 3,
    "force_offset": 4,
    "torque_offset": 4,
    "center_of_mass": 4,
    "mean_relative_error_pct": 2,
}
"""Decimal places the paper printed each quantity to."""


def paper_csv_path():
    """Path of the bundled copy of the paper's Table 1 + Table 2."""
    return resources.files("ftkin") / "data" / "paper_poses.csv"


def paper_samples() -> Samples:
    """The paper's nine poses as :class:`Samples` (orientations from Euler angles)."""
    with resources.as_file(paper_csv_path()) as path:
        return load_samples(path).samples


def paper_calibration(method: str = "linear") -> CalibrationResult:
    """Calibrate the paper's data with ``g = 9.8`` as the paper did."""
    return calibrate(paper_samples(), method=method, g=PAPER_G)


def ftkin_values(result: CalibrationResult) -> dict[str, np.ndarray]:
    """ftkin's numbers under the keys of :data:`PAPER_RESULTS`."""
    return {
        "base_tilt_deg": np.array(result.base_tilt_deg),
        "tool_weight": np.array(result.tool_weight),
        "force_offset": result.force_offset,
        "torque_offset": result.torque_offset,
        "center_of_mass": result.center_of_mass,
        "mean_relative_error_pct": 100.0 * result.mean_relative_error,
    }


def comparison_table(result: CalibrationResult) -> str:
    """Side-by-side text table: the paper's printed values and ftkin's, rounded alike."""
    ours = ftkin_values(result)
    lines = [f"{'quantity':<26}{'paper':<44}{'ftkin':<44}match"]
    for key, printed in PAPER_RESULTS.items():
        decimals = PRINTED_DECIMALS[key]
        rounded = np.round(np.atleast_1d(ours[key]), decimals) + 0.0
        paper_text = ", ".join(f"{value:.{decimals}f}" for value in np.atleast_1d(printed))
        ours_text = ", ".join(f"{value:.{decimals}f}" for value in rounded)
        match = "yes" if paper_text == ours_text else "NO"
        lines.append(f"{key:<26}{paper_text:<44}{ours_text:<44}{match}")
    return "\n".join(lines)
