"""What the 3D view shows: one frame per calibration pose or per row of a replayed log, and the
table of its vectors (``ftkin view`` prints it; :class:`~ftkin.viz.viewer.CalibrationViewer`
draws the frames).

Readings are those of the real sensor (the calibration's reading signs and mount applied,
:func:`~ftkin.calibration.conventions.as_real_sensor`). With a drifting calibration and reading
times, each reading is shifted by ``bias(t) − bias`` so that the viewer, which subtracts the
calibration's bias, subtracts the bias the reading had: the rule of ``ftkin compensate``
(:func:`~ftkin.control.bias_checks.bias_at_times`: the trajectory inside the recording, the
calibration's bias elsewhere; its clock warnings included). Samples read with another arm than
the calibration's are warned of (:mod:`ftkin.calibration.samples_arm`).
"""

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..calibration.conventions import as_real_sensor
from ..calibration.samples import Samples
from ..calibration.samples_arm import warn_if_samples_arm_differs
from ..control.bias_checks import bias_at_times
from ..exceptions import InvalidInput
from .contact_sheet import force_angle_deg

TABLE_ROWS = 40
"""Rows of :func:`vector_table` (the rest are counted on a last line)."""
SHEET_CELLS = 25
"""Most cells of a contact sheet (more poses or log rows are subsampled evenly)."""
REPLAY_RATE = 30.0
"""Rows per second [1/s] a replayed log without a time column is shown at."""


@dataclass(frozen=True)
class ViewFrames:
    """What to show, one entry per pose (or log row).

    Attributes:
        labels: ``"pose K"`` (pose id of the samples) or ``"row K"`` (row index of the log).
        raw_wrenches: ``(N, 6)`` real-sensor readings [N, N·m], shifted by the drift (above).
        configurations: ``(N, nq)`` joint angles [rad], or None (orientations only).
        rotations: ``(N, 3, 3)`` ``R_BS`` of the real sensor.
        times: ``(N,)`` times to animate at [s] (a replay), or None (poses, held in turn).
    """

    labels: tuple[str, ...]
    raw_wrenches: np.ndarray
    configurations: np.ndarray | None
    rotations: np.ndarray
    times: np.ndarray | None

    def index(self, pose: int, replay: bool) -> int:
        """Index of pose id ``pose`` (or of log row ``pose`` in a replay).

        Raises:
            InvalidInput: no such pose or row (the message lists those there are).
        """
        wanted = f"row {pose}" if replay else f"pose {pose}"
        if wanted not in self.labels:
            shown = ", ".join(self.labels[:12]) + (" ..." if len(self.labels) > 12 else "")
            raise InvalidInput(f"--pose {pose}: no {wanted}; available: {shown}")
        return self.labels.index(wanted)

    def placement(self, rows=slice(None)) -> dict:
        """The keyword the viewer places ``rows`` by: joint angles when known, else sensor
        orientations."""
        if self.configurations is None:
            return {"rotations": self.rotations[rows]}
        return {"configurations": self.configurations[rows]}


def evenly(count: int, most: int) -> np.ndarray:
    """Indices of at most ``most`` of ``count`` rows, evenly spaced (all of them if they fit)."""
    return np.unique(np.linspace(0, count - 1, min(count, most)).round().astype(int))


def _at_reading_bias(calibration, wrenches: np.ndarray, times) -> np.ndarray:
    """``wrenches`` shifted by ``bias(t) − bias`` (nothing to shift without times)."""
    if times is None:
        return wrenches
    times = np.asarray(times, dtype=float)
    return wrenches - (bias_at_times(calibration.drift, calibration.bias, times) - calibration.bias)


def pose_frames(samples: Samples, calibration) -> ViewFrames:
    """One frame per pose of calibration ``samples``: the mean reading, orientation and joint
    angles of each pose, in the order the poses first appear."""
    warn_if_samples_arm_differs(samples, calibration)
    samples = as_real_sensor(samples, calibration)
    averages = samples.pose_averages()
    configurations = (
        None
        if samples.joint_positions is None
        else np.array(
            [
                samples.joint_positions[samples.pose_ids == pid].mean(axis=0)
                for pid in averages.pose_ids
            ]
        )
    )
    return ViewFrames(
        tuple(f"pose {int(pid)}" for pid in averages.pose_ids),
        _at_reading_bias(calibration, averages.wrenches, averages.times),
        configurations,
        averages.rotations,
        None,
    )


def replay_frames(
    samples: Samples, calibration, max_frames: int, source: str = "the log"
) -> ViewFrames:
    """At most ``max_frames`` evenly spaced rows of a recorded run, at their times [s] (without a
    time column: :data:`REPLAY_RATE` rows per second).

    Raises:
        InvalidInput: the time column decreases somewhere (``source`` names the file).
    """
    warn_if_samples_arm_differs(samples, calibration)
    samples = as_real_sensor(samples, calibration)
    times = samples.times
    if times is not None and np.any(np.diff(times) < 0):
        raise InvalidInput(f"{source}: the time column must not decrease (seconds since the start)")
    rows = evenly(len(samples), max_frames)
    return ViewFrames(
        tuple(f"row {int(r)}" for r in rows),
        _at_reading_bias(
            calibration, samples.wrenches[rows], None if times is None else times[rows]
        ),
        None if samples.joint_positions is None else samples.joint_positions[rows],
        samples.rotations[rows],
        rows / REPLAY_RATE if times is None else times[rows],
    )


def outlier_indices(labels: Sequence[str], calibration) -> list[int]:
    """Indices of ``labels`` that name a pose the calibration flagged as an outlier."""
    diagnostics = calibration.diagnostics
    flagged = {
        f"pose {int(pid)}"
        for pid in (diagnostics.outlier_pose_ids if diagnostics is not None else ())
    }
    return [i for i, label in enumerate(labels) if label in flagged]


def save_frames_sheet(
    viewer, frames: ViewFrames, calibration, path, *, title: str = "", most: int = SHEET_CELLS
) -> tuple[int, int]:
    """Write a contact sheet (.png) of at most ``most`` evenly spaced frames drawn in ``viewer``
    (a :class:`~ftkin.viz.viewer.CalibrationViewer`), the calibration's outlier poses outlined;
    returns ``(cells, outliers)``."""
    from .contact_sheet import save_contact_sheet, sheet_cells

    rows = evenly(len(frames.labels), most)
    labels = [frames.labels[k] for k in rows]
    outliers = outlier_indices(labels, calibration)
    cells = sheet_cells(
        viewer, labels, frames.raw_wrenches[rows], outliers=outliers, **frames.placement(rows)
    )
    save_contact_sheet(cells, path, title=title)
    return len(cells), len(outliers)


@dataclass(frozen=True)
class VectorRow:
    """One line of the view's table (from a :class:`~ftkin.viz.viewer.PoseVectors`).

    Attributes:
        label: The frame's label.
        measured_force: ``|F − F0|`` [N].
        gravity_force: ``|Gs|``, the predicted tool weight [N].
        angle_deg: Angle between the two [deg] (NaN when one is zero); small at a good
            calibration.
        contact_force: ``|F′|`` [N].
        contact_torque: ``|M′|`` [N·m].
    """

    label: str
    measured_force: float
    gravity_force: float
    angle_deg: float
    contact_force: float
    contact_torque: float


def vector_rows(labels: Sequence[str], vectors) -> list[VectorRow]:
    """The table's numbers of each frame's drawn vectors."""
    return [
        VectorRow(
            label,
            float(np.linalg.norm(v.measured_force)),
            float(np.linalg.norm(v.gravity_force)),
            force_angle_deg(v.measured_force, v.gravity_force),
            float(np.linalg.norm(v.contact_wrench[:3])),
            float(np.linalg.norm(v.contact_wrench[3:])),
        )
        for label, v in zip(labels, vectors)
    ]


def vector_table(labels: Sequence[str], vectors, most: int = TABLE_ROWS) -> str:
    """The table ``ftkin view`` prints: one line per frame (the first ``most``)."""
    rows = vector_rows(list(labels)[:most], list(vectors)[:most])
    lines = [
        f"  {'':<10}{'|F-F0| N':>10}{'|Gs| N':>10}{'angle deg':>11}{'|F′| N':>10}{'|M′| N·m':>10}"
    ]
    lines += [
        f"  {r.label:<10}{r.measured_force:>10.4f}{r.gravity_force:>10.4f}{r.angle_deg:>11.3f}"
        f"{r.contact_force:>10.4f}{r.contact_torque:>10.4f}"
        for r in rows
    ]
    if len(labels) > most:
        lines.append(f"  ... {len(labels) - most} more")
    return "\n".join(lines)
