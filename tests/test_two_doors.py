"""One bad input, one refusal, through both doors (issue 38): the library and ``ftkin``.

Each case is a small malformed file in a shape users have (a samples CSV, a moving recording,
a calibration JSON, a log to compensate) with the CLI command that reads it and the library
calls that command makes, in the same order:

* ``calibrate S.csv``: ``load_samples(S, segments=SegmentParameters())``, then
  ``check_sample_conventions(loaded.table, arm, declared_wrench_units(read_header(S)))``, then
  ``calibrate(loaded.samples)``;
* ``calibrate --dynamic M.csv``: ``load_motion_csv(M, arm).motion_samples(arm)``, then
  ``calibrate_dynamic``;
* ``compensate C.json L.csv``: ``load_calibration(C)``, the arm it records, ``Compensator``,
  ``load_samples(L, arm)``, ``check_log_conventions(loaded.table, arm, calibration)``,
  ``compensate_samples``; with ``--track-load`` then
  ``loaded.table.booleans(GRIPPER_COLUMN, GRIPPER_STATES)``;
* ``export C.json --format F``: ``export_text(load_calibration(C), F)``;
* ``rezero C.json --q .. --wrench ..``: ``Compensator(load_calibration(C)).rezero(q, wrench)``;
* ``report C.json S.csv``: ``load_calibration``, ``load_samples(S, arm, SegmentParameters())``,
  ``save_report``;
* ``doctor S.csv``: ``diagnose_samples(S)``;
* ``evaluate-poses P.csv``: ``pose_set_from_table(read_table(P))``, then ``evaluate_poses`` with
  the command's default expectation (50 readings per pose; the library's default is 1).

The rule both doors keep, checked for every case:

1. the library raises the case's :class:`~ftkin.exceptions.FtkinError` subclass, its message
   holding the hand-derived fragment (the file's line counted by hand, the value written);
2. ``ftkin.cli.main`` on the same file returns 2, prints no traceback, and its error is one
   stderr line (the last; warnings may come before it) that is ``"ftkin: error: "`` followed by
   the library's message, word for word;
3. after the library's message the CLI may add one suffix of its own, and only one listed in
   :data:`CLI_SUFFIXES`: the command-line spelling of what a library caller does by leaving a
   call out (e.g. not calling ``check_log_conventions``), never advice the library's message
   lacks. No other prefix, no other words.

The files are written by hand (a header line, then rows), each row of the valid base file from
the bundled arm's forward kinematics and the paper-like tool (``truth.predict``); the mutations
(an empty file, a cell replaced, a column dropped, a unit changed) are made on the text.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

import ftkin
from ftkin.cli import main
from ftkin.exceptions import (
    CalibrationFileError,
    ConventionMistake,
    InvalidInput,
    InvalidSamples,
    SuspectConvention,
    UnobservableParameters,
)
from ftkin.sim.sensor import paper_like_truth

WRENCH = ["fx", "fy", "fz", "mx", "my", "mz"]
JOINTS = [f"q{i}" for i in range(1, 7)]
MATRIX = [f"r{row}{column}" for row in (1, 2, 3) for column in (1, 2, 3)]
POSES = 8
RATE = 100.0  # [Hz] of the moving recordings

CLI_SUFFIXES = (" (--no-convention-check compensates the log as given)",)
"""What the CLI may add after the library's message: the flag that skips a check a library
caller skips by not calling it (``compensate``: :func:`~ftkin.io.log_conventions.
check_log_conventions`)."""


def _row(cells) -> str:
    return ",".join(cell if isinstance(cell, str) else repr(float(cell)) for cell in cells)


def _csv(header, rows) -> str:
    return ",".join(header) + "\n" + "".join(_row(row) + "\n" for row in rows)


@dataclass(frozen=True)
class Base:
    """The valid inputs the cases spoil: joint angles ``q`` [rad] of eight poses, their ``R_BS``,
    the readings there [N, N·m], and a calibration file made from them."""

    folder: Path
    q: np.ndarray
    rotations: np.ndarray
    wrenches: np.ndarray
    calibration: Path
    arm: ftkin.Arm

    def samples_text(self, wrenches=None, q=None) -> str:
        wrenches = self.wrenches if wrenches is None else wrenches
        q = self.q if q is None else q
        return _csv(["pose", *JOINTS, *WRENCH], [[i, *q[i], *wrenches[i]] for i in range(POSES)])

    def rotation_text(self, header, orientation) -> str:
        """A samples CSV with ``orientation`` ``(8, k)`` in the columns ``header``."""
        rows = [[i, *orientation[i], *self.wrenches[i]] for i in range(POSES)]
        return _csv(["pose", *header, *WRENCH], rows)

    def motion_text(self, rows=400, amplitude=0.4, time_scale=1.0, edit=None) -> str:
        """A moving recording at :data:`RATE`: each joint a sine about pose 0 (``amplitude``
        [rad], none: still), the readings of the static tool (the inertial term plays no role in
        a refusal), ``t`` multiplied by ``time_scale``."""
        t = np.arange(rows) / RATE
        phase = np.outer(2 * np.pi * 0.3 * t, 0.5 + 0.37 * np.arange(1, 7))
        q = self.q[0] + amplitude * np.sin(phase)
        wrenches = paper_like_truth().predict(self.arm.rotation_sensor_to_base(q))
        table = [[repr(float(t[i] * time_scale)), *q[i], *wrenches[i]] for i in range(rows)]
        if edit is not None:
            table = edit(table)
        return _csv(["t", *JOINTS, *WRENCH], table)

    def calibration_text(self, edit) -> str:
        document = json.loads(self.calibration.read_text())
        edit(document)
        return json.dumps(document)


@pytest.fixture(scope="module")
def base(tmp_path_factory, arm, truth) -> Base:
    folder = tmp_path_factory.mktemp("two_doors")
    rng = np.random.default_rng(38)
    q = arm.random_configurations(POSES, rng, margin=0.3)
    rotations = arm.rotation_sensor_to_base(q)
    wrenches = truth.predict(rotations) + rng.normal(0.0, [0.02] * 3 + [0.002] * 3, (POSES, 6))
    samples = folder / "good.csv"
    text = _csv(["pose", *JOINTS, *WRENCH], [[i, *q[i], *wrenches[i]] for i in range(POSES)])
    samples.write_text(text)
    calibration = folder / "good.json"
    loaded = ftkin.load_samples(samples)
    ftkin.save_calibration(ftkin.calibrate(loaded.samples), calibration)
    return Base(folder, q, rotations, wrenches, calibration, arm)


# --- the doors: the command line and the library calls behind it ---------------------------


def _calibrate_api(base: Base, path: Path):
    from ftkin.io.column_spelling import declared_wrench_units
    from ftkin.io.csv_table import read_header
    from ftkin.io.static_segments import SegmentParameters
    from ftkin.io.table_readings import check_sample_conventions

    loaded = ftkin.load_samples(path, segments=SegmentParameters())
    check_sample_conventions(loaded.table, None, declared_wrench_units(read_header(path)))
    return ftkin.calibrate(loaded.samples)


def _dynamic_api(base: Base, path: Path):
    from ftkin.io import load_motion_csv

    recording = load_motion_csv(path, base.arm)
    return ftkin.calibrate_dynamic(recording.motion_samples(base.arm, None))


def _compensate_api(base: Base, calibration: Path, log: Path):
    from ftkin.io.log_conventions import check_log_conventions

    loaded_calibration = ftkin.load_calibration(calibration)
    arm = loaded_calibration.kinematics.build_arm()
    compensator = ftkin.Compensator(loaded_calibration, arm)
    loaded = ftkin.load_samples(log, arm)
    check_log_conventions(loaded.table, arm, loaded_calibration)
    return compensator.compensate_samples(loaded.samples)


def _track_load_api(base: Base, path: Path):
    """``compensate --track-load``: the compensation's calls, then the gripper column."""
    from ftkin.control.load_track import GRIPPER_COLUMN, GRIPPER_STATES

    _compensate_api(base, base.calibration, path)
    return ftkin.load_samples(path).table.booleans(GRIPPER_COLUMN, GRIPPER_STATES)


def _export_api(base: Base, path: Path, fmt: str = "ft-calib"):
    from ftkin.io.export import export_text

    return export_text(ftkin.load_calibration(path), fmt)


REZERO_Q, REZERO_WRENCH = [0.3] * 6, [0.5, -0.2, -3.0, 0.01, 0.02, 0.0]


def _rezero_api(base: Base, path: Path, q=REZERO_Q, wrench=REZERO_WRENCH):
    return ftkin.Compensator(ftkin.load_calibration(path)).rezero(np.array(q), np.array(wrench))


def _evaluate_api(base: Base, path: Path):
    from ftkin.io.pose_table import pose_set_from_table
    from ftkin.io.samples_csv import read_table
    from ftkin.planning.evaluation import ExpectedCalibration, evaluate_poses

    poses = pose_set_from_table(read_table(path), None)
    # evaluate-poses' defaults: the paper's tool and noise, 50 readings per pose
    expected = ExpectedCalibration(3.15, (0.0, 0.0, 0.047), readings_per_pose=50)
    return evaluate_poses(poses.rotations, expected)


def _report_api(base: Base, path: Path):
    from ftkin.io.static_segments import SegmentParameters
    from ftkin.viz.report import save_report

    calibration = ftkin.load_calibration(base.calibration)
    arm = calibration.kinematics.build_arm()
    loaded = ftkin.load_samples(path, arm, SegmentParameters())
    return save_report(calibration, loaded.samples, base.folder / "report.png")


def _doctor_api(base: Base, path: Path):
    from ftkin.io import diagnose_samples

    return diagnose_samples(path)


Door = tuple[Callable[[Base, Path], list], Callable[[Base, Path], object]]
DOORS: dict[str, Door] = {
    "calibrate": (lambda b, p: ["calibrate", p], _calibrate_api),
    "calibrate --dynamic": (lambda b, p: ["calibrate", "--dynamic", p], _dynamic_api),
    "compensate": (
        lambda b, p: ["compensate", b.calibration, p, "-o", b.folder / "out.csv"],
        lambda b, p: _compensate_api(b, b.calibration, p),
    ),
    "compensate CALIB": (  # a malformed calibration, a good log
        lambda b, p: ["compensate", p, b.folder / "good.csv", "-o", b.folder / "out.csv"],
        lambda b, p: _compensate_api(b, p, b.folder / "good.csv"),
    ),
    "compensate --track-load": (
        lambda b, p: [
            *("compensate", b.calibration, p, "-o", b.folder / "out.csv", "--track-load"),
            *("--noise-force", "0.02", "--noise-torque", "0.002"),
        ],
        _track_load_api,
    ),
    "export": (
        lambda b, p: ["export", p, "--format", "ft-calib", "-o", b.folder / "out.yaml"],
        _export_api,
    ),
    "export franka-load": (
        lambda b, p: ["export", p, "--format", "franka-load", "-o", b.folder / "out.yaml"],
        lambda b, p: _export_api(b, p, "franka-load"),
    ),
    "rezero": (
        lambda b, p: [
            "rezero",
            p,
            "--q",
            *map(str, REZERO_Q),
            "--wrench",
            *map(str, REZERO_WRENCH),
            "-o",
            b.folder / "out.json",
        ],
        _rezero_api,
    ),
    "doctor": (lambda b, p: ["doctor", p], _doctor_api),
    "report": (
        lambda b, p: ["report", b.calibration, p, "-o", b.folder / "report.png"],
        _report_api,
    ),
    "evaluate-poses": (lambda b, p: ["evaluate-poses", p], _evaluate_api),
}


# --- the malformed inputs -------------------------------------------------------------------


def _cell(text: str, line: int, column: str, value: str) -> str:
    """``text`` with the cell of ``column`` on 1-based ``line`` replaced by ``value``."""
    lines = text.splitlines()
    header = lines[0].split(",")
    cells = lines[line - 1].split(",")
    cells[header.index(column)] = value
    lines[line - 1] = ",".join(cells)
    return "\n".join(lines) + "\n"


def _columns(text: str, keep: Callable[[str], bool], extra: str | None = None) -> str:
    """``text`` with only the columns whose name ``keep`` accepts, and ``extra`` repeated."""
    lines = [line.split(",") for line in text.splitlines()]
    indices = [i for i, name in enumerate(lines[0]) if keep(name)]
    if extra is not None:
        indices.append(lines[0].index(extra))
    return "".join(",".join(cells[i] for i in indices) + "\n" for cells in lines)


def _columns_added(text: str, name: str, cells: list[str]) -> str:
    """``text`` with a column ``name`` of ``cells`` (one per data row) appended."""
    lines = text.splitlines()
    out = [lines[0] + "," + name] + [line + "," + cell for line, cell in zip(lines[1:], cells)]
    return "\n".join(out) + "\n"


def _drop_arm(document: dict) -> None:
    """A calibration document as made from orientations: no arm recorded."""
    for key in ("kinematics", "urdf", "sensor_frame"):
        document.pop(key, None)


def _flip_rows(rows, i: int, j: int):
    """The recording with row ``i``'s time replaced by row ``j``'s."""
    rows = [list(row) for row in rows]
    rows[i][0] = rows[j][0]
    return rows


def _euler_zyx_deg(rotations) -> np.ndarray:
    """``alpha, beta, gamma`` [deg] with ``R = Rz(alpha) Ry(beta) Rx(gamma)``, by SciPy (not
    ftkin)."""
    from scipy.spatial.transform import Rotation

    return Rotation.from_matrix(rotations).as_euler("ZYX", degrees=True)


def _quaternion_xyzw(rotations) -> np.ndarray:
    from scipy.spatial.transform import Rotation

    return Rotation.from_matrix(rotations).as_quat()  # SciPy's order: x, y, z, w


def _scaled(wrenches, factors):
    return np.asarray(wrenches) * np.asarray(factors)


@dataclass(frozen=True)
class Case:
    """A malformed file (``name``, its text from the base inputs), the door it goes through, the
    error class the library raises and a fragment of its message derived by hand."""

    name: str
    door: str
    text: Callable[[Base], str]
    error: type
    fragment: str


LINE_3 = 3  # the second data row (line 1 is the header)
LATIN1_NOTE = "# recorded at 20 \udcb0C\n"  # a lone surrogate: written as the raw byte 0xb0

CASES = [
    # samples CSV: the file and its cells
    Case("empty.csv", "calibrate", lambda b: "", InvalidSamples, "file is empty"),
    Case(
        "header.csv",
        "calibrate",
        lambda b: b.samples_text().splitlines()[0] + "\n",
        InvalidSamples,
        "no data rows after the header",
    ),
    Case(
        "text_cell.csv",
        "calibrate",
        lambda b: _cell(b.samples_text(), LINE_3, "fy", "abc"),
        InvalidSamples,
        "line 3: column 'fy': 'abc' is not a number",
    ),
    Case(
        "nan_cell.csv",
        "calibrate",
        lambda b: _cell(b.samples_text(), LINE_3, "mz", "nan"),
        InvalidSamples,
        "line 3: column 'mz': 'nan' is not finite",
    ),
    Case(
        "inf_cell.csv",
        "calibrate",
        lambda b: _cell(b.samples_text(), LINE_3, "q2", "-inf"),
        InvalidSamples,
        "line 3: column 'q2': '-inf' is not finite",
    ),
    Case(
        "overflow_cell.csv",
        "calibrate",
        lambda b: _cell(b.samples_text(), LINE_3, "fx", "1e999"),
        InvalidSamples,
        "line 3: column 'fx': '1e999' is not finite",
    ),
    Case(
        "duplicated_column.csv",
        "calibrate",
        lambda b: _columns(b.samples_text(), lambda name: True, extra="fz"),
        InvalidSamples,
        "line 1: duplicated column(s) ['fz'] in the header",
    ),
    Case(
        "no_torques.csv",
        "calibrate",
        lambda b: _columns(b.samples_text(), lambda name: name not in ("mx", "my", "mz")),
        InvalidSamples,
        "missing wrench column(s) ['mx', 'my', 'mz']",
    ),
    Case(
        "five_joints.csv",
        "calibrate",
        lambda b: _columns(b.samples_text(), lambda name: name != "q6"),
        InvalidSamples,
        "joint columns ['q1', 'q2', 'q3', 'q4', 'q5'] do not match the arm's 6 joints",
    ),
    Case(
        "degrees.csv",
        "calibrate",
        lambda b: b.samples_text(q=np.rad2deg(b.q)),
        InvalidSamples,
        "joint angles must be in radians",
    ),
    Case(
        "absurd_forces.csv",  # 1e6 × a 3.16 N tool (raw counts, µN): 3.16e6 > 1e6
        "calibrate",
        lambda b: b.samples_text(wrenches=b.wrenches * 1e6),
        InvalidSamples,
        "beyond ±1e+06: expected N (fx, fy, fz) and N·m",
    ),
    Case(
        "decimal_commas.csv",  # a spreadsheet's export: semicolons, decimal commas
        "calibrate",
        lambda b: b.samples_text().replace(",", ";").replace(".", ","),
        InvalidSamples,
        "line 2: column 'q1'",
    ),
    Case(
        "latin1.csv",  # a note in Latin-1 (the ° of 20 °C is the byte 0xb0)
        "calibrate",
        lambda b: LATIN1_NOTE + b.samples_text(),
        InvalidSamples,
        "line 1: byte 0xb0 is not UTF-8 text (invalid start byte): save the file as UTF-8",
    ),
    # samples CSV: orientations given directly
    Case(
        "not_a_rotation.csv",  # the third matrix scaled by 1.1: RᵀR − I has 1.21 − 1 = 0.21
        "calibrate",
        lambda b: b.rotation_text(
            MATRIX,
            b.rotations.reshape(POSES, 9) * np.where(np.arange(POSES) == 2, 1.1, 1.0)[:, None],
        ),
        InvalidSamples,
        "line 4: rotation matrix r11..r33 is not a rotation: RᵀR off the identity by 0.21",
    ),
    Case(
        "not_unit_quaternion.csv",  # the fifth quaternion (line 6) scaled by 1.1: norm 1.1
        "calibrate",
        lambda b: b.rotation_text(
            ["qw", "qx", "qy", "qz"],
            _quaternion_xyzw(b.rotations)[:, [3, 0, 1, 2]]
            * np.where(np.arange(POSES) == 4, 1.1, 1.0)[:, None],
        ),
        InvalidSamples,
        "line 6: quaternion [qw, qx, qy, qz] has norm 1.100000; expected a unit quaternion",
    ),
    Case(
        "transposed.csv",
        "calibrate",
        lambda b: b.rotation_text(MATRIX, np.transpose(b.rotations, (0, 2, 1)).reshape(POSES, 9)),
        ConventionMistake,
        "the data fit when read with the matrix transposed",
    ),
    Case(
        "quaternion_xyzw.csv",  # x,y,z,w under the names qw,qx,qy,qz
        "calibrate",
        lambda b: b.rotation_text(["qw", "qx", "qy", "qz"], _quaternion_xyzw(b.rotations)),
        ConventionMistake,
        "the data fit when read with the quaternion as x,y,z,w",
    ),
    Case(
        "euler_radians.csv",
        "calibrate",
        lambda b: b.rotation_text(
            ["alpha", "beta", "gamma"], np.deg2rad(_euler_zyx_deg(b.rotations))
        ),
        ConventionMistake,
        "the data fit when read with Euler angles in radians",
    ),
    # samples CSV: the wrench columns in another convention
    Case(
        "torques_nmm.csv",  # a COM 47 mm read as 47 m: only plausible in N·mm
        "calibrate",
        lambda b: b.samples_text(wrenches=_scaled(b.wrenches, [1] * 3 + [1000] * 3)),
        ConventionMistake,
        "torques in N·mm",
    ),
    Case(
        "forces_torques_swapped.csv",
        "calibrate",
        lambda b: b.samples_text(wrenches=b.wrenches[:, [3, 4, 5, 0, 1, 2]]),
        ConventionMistake,
        "force and torque columns swapped",
    ),
    Case(
        "y_reversed.csv",
        "calibrate",
        lambda b: b.samples_text(wrenches=_scaled(b.wrenches, [1, -1, 1, 1, -1, 1])),
        ConventionMistake,
        "the sensor's y axis reversed",
    ),
    Case(
        "reaction.csv",  # every reading negated: the weight points up (180° from base −z)
        "calibrate",
        lambda b: b.samples_text(wrenches=-b.wrenches),
        SuspectConvention,
        "points 180° away from the expected gravity direction",
    ),
    # samples CSV: poses that cannot determine the tool
    Case(
        "single_pose.csv",
        "calibrate",
        lambda b: "\n".join(b.samples_text().splitlines()[:2]) + "\n",
        UnobservableParameters,
        "only 1 distinct pose(s); at least 3 static poses",
    ),
    Case(
        "one_orientation.csv",
        "calibrate",
        lambda b: b.samples_text(q=np.repeat(b.q[:1], POSES, axis=0)),
        UnobservableParameters,
        "the sensor orientations are all alike",
    ),
    # the same files through the other readers of a samples CSV
    Case("empty.csv", "doctor", lambda b: "", InvalidSamples, "file is empty"),
    Case(
        "duplicated_column.csv",
        "doctor",
        lambda b: _columns(b.samples_text(), lambda name: True, extra="fz"),
        InvalidSamples,
        "duplicated column(s) ['fz']",
    ),
    Case(
        "five_joints.csv",
        "doctor",
        lambda b: _columns(b.samples_text(), lambda name: name != "q6"),
        InvalidSamples,
        "do not match the arm's 6 joints",
    ),
    Case(
        "degrees.csv",
        "evaluate-poses",
        lambda b: b.samples_text(q=np.rad2deg(b.q)),
        InvalidSamples,
        "joint angles must be in radians",
    ),
    Case(
        "not_a_rotation.csv",
        "evaluate-poses",
        lambda b: b.rotation_text(
            MATRIX,
            b.rotations.reshape(POSES, 9) * np.where(np.arange(POSES) == 2, 1.1, 1.0)[:, None],
        ),
        InvalidSamples,
        "line 4: rotation matrix r11..r33 is not a rotation",
    ),
    Case(
        "one_orientation.csv",
        "evaluate-poses",
        lambda b: b.samples_text(q=np.repeat(b.q[:1], POSES, axis=0)),
        UnobservableParameters,
        "the poses cannot determine",
    ),
    Case(
        "five_joints.csv",
        "report",
        lambda b: _columns(b.samples_text(), lambda name: name != "q6"),
        InvalidSamples,
        "do not match the arm's 6 joints",
    ),
    Case(
        "nan_cell.csv",
        "report",
        lambda b: _cell(b.samples_text(), LINE_3, "mz", "nan"),
        InvalidSamples,
        "line 3: column 'mz': 'nan' is not finite",
    ),
    # a log to compensate with the calibration of the bundled six-joint arm
    Case(
        "seven_joints.csv",
        "compensate",
        lambda b: _csv(
            ["pose", *JOINTS, "q7", *WRENCH],
            [[i, *b.q[i], 0.0, *b.wrenches[i]] for i in range(POSES)],
        ),
        InvalidSamples,
        "joint columns ['q1', 'q2', 'q3', 'q4', 'q5', 'q6', 'q7'] do not match the arm's 6 joints",
    ),
    Case(
        "degrees.csv",
        "compensate",
        lambda b: b.samples_text(q=np.rad2deg(b.q)),
        InvalidSamples,
        "joint angles must be in radians",
    ),
    Case(
        "text_cell.csv",
        "compensate",
        lambda b: _cell(b.samples_text(), LINE_3, "fy", "abc"),
        InvalidSamples,
        "line 3: column 'fy': 'abc' is not a number",
    ),
    Case(
        "absurd_forces.csv",
        "compensate",
        lambda b: b.samples_text(wrenches=b.wrenches * 1e6),
        InvalidSamples,
        "beyond ±1e+06",
    ),
    Case(
        "quaternion_xyzw.csv",
        "compensate",
        lambda b: b.rotation_text(["qw", "qx", "qy", "qz"], _quaternion_xyzw(b.rotations)),
        ConventionMistake,
        "the log fits the calibration when read with the quaternion as x,y,z,w",
    ),
    Case(
        "euler_radians.csv",
        "compensate",
        lambda b: b.rotation_text(
            ["alpha", "beta", "gamma"], np.deg2rad(_euler_zyx_deg(b.rotations))
        ),
        ConventionMistake,
        "read with Euler angles in radians",
    ),
    Case(
        "torques_nmm.csv",
        "compensate",
        lambda b: b.samples_text(wrenches=_scaled(b.wrenches, [1] * 3 + [1000] * 3)),
        ConventionMistake,
        "read with torques in N·mm",
    ),
    Case(
        "reaction.csv",
        "compensate",
        lambda b: b.samples_text(wrenches=-b.wrenches),
        ConventionMistake,
        "read with the readings negated",
    ),
    Case(
        "gripper_yes.csv",  # the fourth row (line 5) says 'yes'
        "compensate --track-load",
        lambda b: _columns_added(b.samples_text(), "gripper", ["1", "1", "1", "yes"] + ["0"] * 4),
        InvalidSamples,
        "line 5: column 'gripper': 'yes' is not 1 or 0; expected 1 (gripper closed) or 0 (open)",
    ),
    # a calibration JSON
    Case("empty.json", "export", lambda b: "", CalibrationFileError, "file is empty"),
    Case(
        "no_force_offset.json",
        "export",
        lambda b: b.calibration_text(lambda d: d.pop("force_offset")),
        CalibrationFileError,
        "key 'force_offset': missing",
    ),
    Case(
        "g_as_text.json",
        "compensate CALIB",
        lambda b: b.calibration_text(lambda d: d.__setitem__("g", "9.81")),
        CalibrationFileError,
        "key 'g': expected a finite number, got '9.81'",
    ),
    Case(
        "negative_mass.json",
        "rezero",
        lambda b: b.calibration_text(lambda d: d.__setitem__("tool_mass", -d["tool_mass"])),
        CalibrationFileError,
        "key 'tool_mass': -",
    ),
    Case(
        "nan_offset.json",  # JSON's NaN literal, which Python's json reads
        "export",
        lambda b: b.calibration_text(
            lambda d: d.__setitem__("force_offset", [0.1, 0.2, 0.3])
        ).replace("0.1, 0.2, 0.3", "NaN, 0.2, 0.3"),
        CalibrationFileError,
        "key 'force_offset'",
    ),
    Case(
        "overflow_weight.json",  # 1e999 reads as inf
        "rezero",
        lambda b: b.calibration_text(lambda d: d.__setitem__("g", 9.5)).replace("9.5", "1e999"),
        CalibrationFileError,
        "key 'g'",
    ),
    Case(
        "a_list.json",
        "compensate CALIB",
        lambda b: "[1, 2, 3]\n",
        CalibrationFileError,
        "expected a JSON object, got list",
    ),
    Case(
        "duplicate_key.json",
        "export",
        lambda b: b.calibration_text(lambda d: None).replace('{"format"', '{"g": 9.8, "format"', 1),
        CalibrationFileError,
        "duplicate key in a JSON object",
    ),
    Case(
        "future_version.json",
        "export",
        lambda b: b.calibration_text(lambda d: d.__setitem__("version", 99)),
        CalibrationFileError,
        "file format version 99",
    ),
    Case(
        "mount_beyond.json",  # a pitch of 120° is no mount of the identity rotation stored
        "compensate CALIB",
        lambda b: b.calibration_text(lambda d: d.__setitem__("mount_rpy_deg", [0.0, 120.0, 0.0])),
        CalibrationFileError,
        "key 'mount_rpy_deg': [0.0, 120.0, 0.0] deg disagrees with mount_rotation",
    ),
    Case(
        "com_in_millimetres.json",  # 47 mm written as 47 m
        "rezero",
        lambda b: b.calibration_text(lambda d: d.__setitem__("center_of_mass", [0.0, 0.0, 47.0])),
        CalibrationFileError,
        "key 'center_of_mass'",
    ),
    Case(
        "no_arm.json",  # as made from orientations: no kinematics, URDF or sensor frame
        "rezero",
        lambda b: b.calibration_text(_drop_arm),
        InvalidInput,
        "this Compensator has no Arm: pass arm= to use joint angles (ftkin: --robot NAME",
    ),
    Case(
        "no_arm.json",
        "export franka-load",
        lambda b: b.calibration_text(_drop_arm),
        InvalidInput,
        "franka-load needs the arm (the centre of mass is written in its flange) and this "
        "calibration records none: pass arm= (ftkin export: --robot NAME or --urdf PATH)",
    ),
    # a moving recording (100 Hz, t in seconds; header on line 1, row k on line k + 2)
    Case(
        "two_rows.csv",
        "calibrate --dynamic",
        lambda b: b.motion_text(rows=2),
        InvalidSamples,
        "2 row(s); a moving recording needs at least 3",
    ),
    Case(
        "still.csv",
        "calibrate --dynamic",
        lambda b: b.motion_text(amplitude=0.0),
        UnobservableParameters,  # one orientation: no advice to drop the inertia (it fails too)
        "too few distinct orientations or motions",
    ),
    Case(
        "milliseconds.csv",  # 100 Hz stamped in ms: 10 "s" apart
        "calibrate --dynamic",
        lambda b: b.motion_text(time_scale=1000.0),
        InvalidSamples,
        "the stamps are 10 s apart",
    ),
    Case(
        "repeated_time.csv",  # row 10 (line 12) repeats row 9's 0.09 s
        "calibrate --dynamic",
        lambda b: b.motion_text(edit=lambda rows: _flip_rows(rows, 10, 9)),
        InvalidSamples,
        "line 12: time stamps do not increase: t = 0.09 s after 0.09 s",
    ),
    Case(
        "time_backwards.csv",  # row 10 (line 12) takes row 5's 0.05 s, after 0.09 s
        "calibrate --dynamic",
        lambda b: b.motion_text(edit=lambda rows: _flip_rows(rows, 10, 5)),
        InvalidSamples,
        "line 12: time stamps do not increase: t = 0.05 s after 0.09 s",
    ),
    Case(
        "degrees.csv",
        "calibrate --dynamic",
        lambda b: b.motion_text(
            edit=lambda rows: [[r[0], *np.rad2deg(np.array(r[1:7], float)), *r[7:]] for r in rows]
        ),
        InvalidSamples,
        "line 2: joint column 'q2' holds -95.2",  # q1 −0.076 rad = −4.4°: inside ±2π
    ),
    Case(
        "header.csv",
        "calibrate --dynamic",
        lambda b: b.motion_text().splitlines()[0] + "\n",
        InvalidSamples,
        "no data rows after the header",
    ),
]


def _cli(argv, capsys) -> tuple[int, str]:
    code = main([str(argument) for argument in argv])
    captured = capsys.readouterr()
    assert "Traceback" not in captured.out + captured.err, captured.err
    return code, captured.err


@pytest.mark.parametrize("case", CASES, ids=[f"{c.door}:{c.name}" for c in CASES])
def test_both_doors_refuse_with_the_same_words(case, base, capsys):
    folder = base.folder / case.door.replace(" ", "_")
    folder.mkdir(exist_ok=True)
    path = folder / case.name
    data = case.text(base).encode("utf-8", "surrogateescape")  # a lone surrogate: a raw byte
    path.write_bytes(data)
    argv, api = DOORS[case.door]
    with pytest.raises(case.error) as info:
        api(base, path)
    message = str(info.value)
    assert case.fragment in message, message
    assert type(info.value) is case.error, type(info.value)
    code, err = _cli(argv(base, path), capsys)
    assert code == 2, err
    line = err.strip().splitlines()[-1]
    assert line.startswith("ftkin: error: "), err
    cli_message = line.removeprefix("ftkin: error: ")
    assert cli_message.startswith(message), f"\nCLI: {cli_message}\nAPI: {message}"
    assert cli_message.removeprefix(message) in ("", *CLI_SUFFIXES), cli_message
    assert path.read_bytes() == data  # an input is never written over


# --- the rule's own edges -------------------------------------------------------------------


@pytest.mark.parametrize(
    ("q", "wrench", "error", "fragment"),
    [
        ([0.3] * 7, REZERO_WRENCH, InvalidInput, "got 7 numbers"),
        ([90.0] * 6, REZERO_WRENCH, InvalidInput, "these look like degrees"),
        ([0.3] * 6, [2e6, 0, 0, 0, 0, 0], InvalidInput, r"beyond ±1e\+06"),
        ([0.3] * 6, [9e5, 0, 0, 0, 0, 0], None, ""),  # below the bound: re-zeroed
    ],
    ids=["seven joints", "degrees", "beyond 1e6 N", "below 1e6 N"],
)
def test_rezero_arguments_through_both_doors(base, capsys, tmp_path, q, wrench, error, fragment):
    """The numbers on rezero's command line are the library's arguments: refused alike on both
    sides of the ±1e6 bound on a reading."""
    argv = ["rezero", base.calibration, "--q", *map(str, q), "--wrench", *map(str, wrench)]
    argv += ["-o", tmp_path / "rezeroed.json"]
    if error is None:
        bias = _rezero_api(base, base.calibration, q, wrench)
        assert main([str(a) for a in argv]) == 0
        np.testing.assert_allclose(
            ftkin.load_calibration(tmp_path / "rezeroed.json").bias, bias, rtol=1e-12
        )
        return
    with pytest.raises(error, match=fragment) as info:
        _rezero_api(base, base.calibration, q, wrench)
    code, err = _cli(argv, capsys)
    assert code == 2 and err.strip().splitlines()[-1] == f"ftkin: error: {info.value}"


def test_the_doctor_prints_the_librarys_verdict(base, capsys):
    """``ftkin doctor`` is a report, not a refusal: its verdict line is the library's, exit 1."""
    path = base.folder / "doctor_xyzw.csv"
    path.write_text(base.rotation_text(["qw", "qx", "qy", "qz"], _quaternion_xyzw(base.rotations)))
    report = _doctor_api(base, path)
    assert (
        report.verdict == "mistake" and report.culprit.reading.name == "the quaternion as x,y,z,w"
    )
    assert main(["doctor", str(path)]) == 1
    assert f"verdict: mistake: {report.message}" in capsys.readouterr().out


def test_convention_check_is_the_librarys(base):
    """The check ``ftkin calibrate`` makes before fitting is the library's
    :func:`~ftkin.io.table_readings.check_sample_conventions`: torques in N·mm give a centre of
    mass 1000 × too far (47 m for 47 mm), which ``calibrate`` alone would fit; the check names
    the unit, and the same data in N·m pass it."""
    from ftkin.io.table_readings import check_sample_conventions

    path = base.folder / "nmm.csv"
    path.write_text(base.samples_text(wrenches=_scaled(base.wrenches, [1] * 3 + [1000] * 3)))
    with pytest.raises(ConventionMistake) as info:
        check_sample_conventions(ftkin.load_samples(path).table)
    assert info.value.reading == "torques in N·mm" and info.value.source == str(path)
    assert str(info.value).startswith(f"{path}: ")
    good = base.folder / "good.csv"
    check_sample_conventions(ftkin.load_samples(good).table)  # nothing raised


@pytest.mark.parametrize("orientations", [1, 8], ids=["one orientation", "eight orientations"])
def test_static_recording_advice_works_when_followed(base, truth, orientations):
    """A recording without angular motion cannot give the inertia. Still at one orientation it
    cannot give the static parameters either: the refusal says so, and offers no advice to drop
    the inertia (which failed the same way). At several orientations (static poses, ``dq = ddq =
    0``) it names the inertia and advises calibrating without it, which then gives the tool's
    mass: 3.15 N / 9.80665 m/s² (the simulated truth's)."""
    from ftkin.calibration.regressor import MotionSamples

    q = np.repeat(base.q[:orientations], 400 // orientations, axis=0)
    zeros = np.zeros_like(q)
    wrenches = truth.predict(base.arm.rotation_sensor_to_base(q))
    motion = MotionSamples.from_joint_trajectory(base.arm, q, zeros, zeros, wrenches)
    with pytest.raises(UnobservableParameters) as info:
        ftkin.calibrate_dynamic(motion)
    advice = "calibrate without the inertia (--no-inertia; estimate_inertia=False)"
    if orientations == 1:
        assert "too few distinct orientations" in str(info.value)
        assert advice not in str(info.value)
        with pytest.raises(UnobservableParameters, match="too few distinct orientations"):
            ftkin.calibrate_dynamic(motion, estimate_inertia=False)
        return
    assert "no angular velocity or acceleration" in str(info.value) and advice in str(info.value)
    result = ftkin.calibrate_dynamic(motion, estimate_inertia=False)
    np.testing.assert_allclose(result.tool_mass, truth.tool_weight / 9.80665, rtol=1e-6)


def test_times_in_milliseconds_warn_alike(base, capsys, caplog):
    """Eight poses 150 s apart stamped in ms read as seconds span 1.05e6 s (12 days: beyond the
    week that warns, within the year that refuses): both doors calibrate and give the same
    warning, with the factor (divide by 1000: 1050 s)."""
    import logging

    path = base.folder / "milliseconds.csv"
    rows = [[150_000.0 * i, *base.q[i], *base.wrenches[i]] for i in range(POSES)]
    path.write_text(_csv(["t", *JOINTS, *WRENCH], rows))
    with caplog.at_level(logging.WARNING, logger="ftkin"):
        _calibrate_api(base, path)
    warned = [r.getMessage() for r in caplog.records if "milliseconds" in r.getMessage()]
    assert len(warned) == 1 and "divide by 1000: 1050 s" in warned[0], caplog.text
    caplog.clear()
    assert main(["calibrate", str(path)]) == 0
    err = capsys.readouterr().err + caplog.text
    assert warned[0] in err, err


def test_a_latin1_file_saved_as_utf8_calibrates(base, capsys):
    """The advice for a file in Latin-1 ("save the file as UTF-8"), followed: the same text
    encoded as UTF-8 is read by both doors (the note is a comment) and calibrates."""
    path = base.folder / "latin1_saved_as_utf8.csv"
    text = (LATIN1_NOTE + base.samples_text()).encode("utf-8", "surrogateescape").decode("latin-1")
    path.write_text(text, encoding="utf-8")
    assert "20 °C" in text
    result = _calibrate_api(base, path)
    assert abs(result.tool_weight - 3.15) < 0.1  # the paper-like tool, with noise
    assert main(["calibrate", str(path)]) == 0, capsys.readouterr().err
