"""The alternative readings of a samples table, for
:func:`ftkin.calibration.conventions.diagnose_readings`.

Besides the wrench alternatives (base frame, reaction, N·mm, one axis
reversed), the orientation columns are read the way people get them wrong:
``alpha,beta,gamma`` holding radians, ``qw,qx,qy,qz`` holding x,y,z,w, joint
columns holding degrees.
"""

import numpy as np

from ..calibration.doctor import ConventionReport, Reading, diagnose_readings, wrench_readings
from ..calibration.model import WRENCH_CHANNELS
from ..calibration.samples import Samples
from ..exceptions import FtkinError
from ..kinematics.rotations import (
    euler_zyx_deg_to_matrix,
    matrix_entries_to_matrix,
    quaternion_to_matrix,
)
from .column_spelling import spelled_table
from .csv_table import Table, missing_columns
from .samples_csv import (
    EULER_COLUMNS,
    MATRIX_COLUMNS,
    QUATERNION_COLUMNS,
    check_wrench_magnitude,
    detect_orientation,
    orientations_from_table,
    pose_ids_from_table,
)


def _reading(name: str, fix: str, rotations, wrenches, pose_ids) -> Reading:
    """The poses of the readings under ``rotations()`` (``R_BS``), or why they cannot be read."""
    try:
        rotations = np.asarray(rotations()).reshape(-1, 3, 3)
        poses = Samples(wrenches, rotations, pose_ids).pose_averages()
    except (FtkinError, ValueError) as error:
        return Reading(name, fix, None, failure=str(error).split(": ")[-1][:80])
    return Reading(name, fix, poses)


def table_readings(table: Table, arm=None) -> list[Reading]:
    """The table as given (first) and under each common mistake; ``arm`` reads joint columns
    (bundled arm by default).

    Raises:
        InvalidSamples: the table has no usable wrench or orientation columns at all.
    """
    from ..kinematics.arm import Arm

    table = spelled_table(table)
    missing_columns(table, WRENCH_CHANNELS, "wrench")
    wrenches = table.floats(WRENCH_CHANNELS)
    check_wrench_magnitude(table, wrenches)
    pose_ids = pose_ids_from_table(table)
    angles = EULER_COLUMNS + QUATERNION_COLUMNS + MATRIX_COLUMNS
    has_angles = any(name in table.header for name in angles)
    if arm is None and not has_angles:
        arm = Arm.default()
    kind, columns = detect_orientation(table, arm.joint_names if arm is not None else None)
    values = table.floats(columns)

    mistakes = {  # the orientation columns read the way people get them wrong
        "euler": (
            "Euler angles in radians",
            "give alpha, beta, gamma in degrees (multiply by 180/π)",
            lambda: euler_zyx_deg_to_matrix(np.rad2deg(values)),
        ),
        "quaternion": (
            "the quaternion as x,y,z,w",
            "name the columns qx,qy,qz,qw (the order they hold)",
            lambda: quaternion_to_matrix(values[:, [3, 0, 1, 2]]),
        ),
        "matrix": (
            "the matrix transposed (R_SB, or the entries column-major)",
            "write R_BS row-major: r12 is row 1, column 2 (swap rIJ and rJI)",
            lambda: np.transpose(matrix_entries_to_matrix(values), (0, 2, 1)),
        ),
        "joints": (
            "joint angles in degrees",
            "give the joint angles in radians (multiply by π/180)",
            lambda: arm.rotation_sensor_to_base(np.deg2rad(values)),
        ),
    }
    given = _reading(
        "the data as given",
        "",
        lambda: orientations_from_table(table, arm).rotations,
        wrenches,
        pose_ids,
    )
    readings = [given, _reading(*mistakes[kind], wrenches, pose_ids)]
    if kind in ("quaternion", "euler"):  # a matrix has its transpose above; FK has no inverse
        readings.append(
            _reading(
                "the orientation inverted (R_SB: base in the sensor frame)",
                "give the sensor's orientation in the base frame, R_BS"
                + (" (conjugate the quaternion: negate qx,qy,qz)" if kind == "quaternion" else ""),
                lambda: np.transpose(orientations_from_table(table, arm).rotations, (0, 2, 1)),
                wrenches,
                pose_ids,
            )
        )
    if given.poses is not None:
        readings.extend(wrench_readings(given.poses))
    return readings


def diagnose_table(table: Table, arm=None) -> ConventionReport:
    """Which convention the table's data fit: see :mod:`ftkin.calibration.conventions`."""
    return diagnose_readings(table_readings(table, arm))


def diagnose_samples(path, arm=None) -> ConventionReport:
    """Read a samples CSV and say which convention its data fit (``ftkin doctor``).

    Args:
        path: Samples CSV (columns as for :func:`~ftkin.io.samples_csv.load_samples`).
        arm: Reads joint columns (default: the bundled arm).

    Returns:
        A :class:`~ftkin.calibration.conventions.ConventionReport`: ``verdict``
        ``"ok"``, ``"suspect"`` or ``"mistake"``, the reading that explains the
        data and the fix.
    """
    from .csv_table import read_table

    return diagnose_table(read_table(path), arm)
