"""The alternative readings of a samples table, for
:func:`ftkin.calibration.conventions.diagnose_readings`.

Besides the wrench alternatives (base frame, reaction, N·mm, one axis
reversed), the orientation columns are read the way people get them wrong:
``alpha,beta,gamma`` holding radians, ``qw,qx,qy,qz`` holding x,y,z,w, joint
columns holding degrees.
"""

import logging

import numpy as np

from ..calibration.doctor import ConventionReport, Reading, diagnose_readings, wrench_readings
from ..calibration.model import WRENCH_CHANNELS
from ..calibration.orientation_mistakes import (  # their names and fixes, the API's too
    CONJUGATE,
    EULER_RADIANS,
    MATRIX_TRANSPOSED,
    ORIENTATION_INVERTED,
    QUATERNION_XYZW,
)
from ..calibration.samples import Samples
from ..exceptions import ConventionMistake, FtkinError
from ..kinematics.rotations import (
    euler_zyx_deg_to_matrix,
    matrix_entries_to_matrix,
    quaternion_to_matrix,
)
from .column_spelling import declared_wrench_units, spelled_table
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

logger = logging.getLogger(__name__)


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
            *EULER_RADIANS,
            lambda: euler_zyx_deg_to_matrix(np.rad2deg(values)),
        ),
        "quaternion": (
            *QUATERNION_XYZW,
            lambda: quaternion_to_matrix(values[:, [3, 0, 1, 2]]),
        ),
        "matrix": (
            *MATRIX_TRANSPOSED,
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
                ORIENTATION_INVERTED[0],
                ORIENTATION_INVERTED[1] + (CONJUGATE if kind == "quaternion" else ""),
                lambda: np.transpose(orientations_from_table(table, arm).rotations, (0, 2, 1)),
                wrenches,
                pose_ids,
            )
        )
    if given.poses is not None:
        readings.extend(wrench_readings(given.poses, joints=kind == "joints"))
    return readings


def diagnose_table(table: Table, arm=None, declared_units=None) -> ConventionReport:
    """Which convention the table's data fit: see :mod:`ftkin.calibration.doctor`.

    ``declared_units``: ``{channel: unit}`` the file's header declares
    (:func:`~ftkin.io.column_spelling.declared_wrench_units`; read here from ``table``'s own
    header when None): a declared torque unit is doubted, never overridden.
    """
    if declared_units is None:
        declared_units = declared_wrench_units(table.header)
    torque_unit = next(
        (declared_units[c] for c in WRENCH_CHANNELS[3:] if c in declared_units), None
    )
    return diagnose_readings(table_readings(table, arm), torque_unit)


def check_sample_conventions(table: Table, arm=None, declared_units=None) -> None:
    """Refuse a samples table whose data fit only under a common mistake; warn (logging) of a
    suspicion: the check ``ftkin calibrate`` makes before fitting, for any caller with a table
    (``load_samples(path).table``), so both refuse the same file with the same words.

    :func:`~ftkin.calibration.estimate.calibrate` reads the orientations under their mistakes
    itself (``convention_check``); the table also shows joint angles in degrees, torques in
    N·mm and force and torque columns swapped or interleaved, which the samples alone do not.

    Args:
        table: The samples table (its ``source`` names it in the message).
        arm: Reads joint columns (None: the bundled arm).
        declared_units: ``{channel: unit}`` the files' headers declare (see
            :func:`diagnose_table`; ``table`` already in SI).

    Raises:
        ConventionMistake: the data fit under another reading (its ``reading`` and ``fix``).
    """
    report = diagnose_table(table, arm, declared_units)
    if report.verdict == "mistake":
        raise ConventionMistake(
            report.message + " (run 'ftkin doctor' for the fit of every reading)",
            table.source,
            report.culprit.reading.name,
            report.culprit.reading.fix,
        )
    if report.verdict == "suspect" and not report.tilted:  # calibrate() warns of a tilt itself
        logger.warning("%s: %s", table.source, report.message)


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


LOG_CHECK_ROWS = 2000
"""Rows of a log (evenly spread) that :func:`log_convention_report` reads under each mistake."""
LOG_QUANTILE = 0.25
"""The quantile of the squared residual per channel that :func:`log_convention_report` judges:
a log may be in contact most of the time (up to three quarters) without being questioned."""
LOG_MISFIT = 5.0
"""The log's residual against the calibration, in units of the calibration's noise per
reading (RMS over the six channels), beyond which its conventions are questioned."""
LOG_RATIO = (4.0, 20.0)
"""How much smaller (in squared residual) another reading must be to be a suspicion (a
warning) and to be the mistake (a refusal)."""


def log_convention_report(table: Table, arm, calibration) -> tuple[str, str, Reading] | None:
    """Whether a log to compensate is in the calibration's conventions: ``(verdict, reason,
    reading)`` when another reading of it (the mistakes of :func:`table_readings`, forces in lbf
    and torques in lbf·in) fits the calibration far better than the log as given, else None.

    The calibration is known, so unlike a calibration's own check this sees units too: the
    residual of each reading is its compensated wrench [N, N·m] (per channel, the
    :data:`LOG_QUANTILE` quantile of its square over up to :data:`LOG_CHECK_ROWS` rows), judged
    in the calibration's noise. A log with contacts is not questioned by them: no other reading
    removes a contact.
    """
    from dataclasses import replace

    diagnostics = calibration.diagnostics
    if diagnostics is None or len(table.rows) < 3:
        return None
    noise = np.asarray(diagnostics.noise.channel_std, dtype=float)
    pick = np.unique(np.linspace(0, len(table.rows) - 1, LOG_CHECK_ROWS).astype(int))
    sample = Table(
        table.source,
        table.header,
        [table.rows[i] for i in pick],
        [table.lines[i] for i in pick],
        table.header_line,
    )
    readings = table_readings(sample, arm)
    given = readings[0]
    if given.poses is None:
        return None
    lbf, lbf_in = 4.4482216152605, 0.1129848290276167  # [N], [N·m]
    for name, factors in (
        ("forces in lbf", [lbf] * 3 + [1.0] * 3),
        ("torques in lbf·in", [1.0] * 3 + [lbf_in] * 3),
        ("forces in lbf and torques in lbf·in", [lbf] * 3 + [lbf_in] * 3),
    ):
        readings.append(
            Reading(
                name,
                "give the wrench in N and N·m (or name the units in the header: 'Fx (lbf)', "
                "'Tx (lbf-in)')",
                replace(given.poses, wrenches=given.poses.wrenches * factors),
            )
        )
    signs = calibration.reading_signs

    def score(reading) -> float:
        poses = reading.poses
        rotations = poses.rotations @ calibration.mount_rotation.T  # the real sensor's
        raw = poses.wrenches if signs is None else poses.wrenches * signs
        contact = raw - calibration.predict(rotations)  # METHOD.md §4, as compensation
        # in SI (the calibration fixes the scale), over the quietest quarter of the rows: a
        # mistake spoils every row, a contact only the rows in contact
        rms = np.sqrt(np.quantile(contact**2, LOG_QUANTILE, axis=0))
        return float(np.sum((rms / noise) ** 2))

    scores = [(score(reading), reading) for reading in readings if reading.poses is not None]
    as_given = scores[0][0]
    if not as_given > 6.0 * LOG_MISFIT**2:
        return None
    best, reading = min(scores[1:], key=lambda item: item[0])
    ratio = as_given / max(best, 1e-300)
    if ratio < LOG_RATIO[0]:
        return None
    verdict = "mistake" if ratio >= LOG_RATIO[1] and best < 6.0 * LOG_MISFIT**2 else "suspect"
    reason = (
        f"the log fits the calibration when read with {reading.name} ({ratio:.3g} times smaller "
        f"squared residual; as given its residual is {np.sqrt(as_given / 6.0):.3g}× the "
        f"calibration's noise): {reading.fix}"
    )
    return verdict, reason, reading
