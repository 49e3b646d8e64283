"""Every combination of the paths the static IMU fit and the fused fit share, end to end through
the command line and the API: the IMU alone or with an ``r11..r33`` orientation; a ``pose``
column or none; repeated readings per pose or one row per pose; the accelerometer in g or m/s².
The readings are built from first principles (not ftkin's model); the fused fit on one row per
pose crashed (issue 37, item 1: ``FusedStaticProblem`` had no ``channel_counts``). And the
interface both problems declare (:mod:`ftkin.calibration.imu_problem_base`)."""

from __future__ import annotations

import json
from dataclasses import dataclass

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import ftkin
from ftkin import Samples
from ftkin.calibration.fused_problem import FusedStaticProblem
from ftkin.calibration.fused_samples import FusedSamples
from ftkin.calibration.imu_fit import covariance_at
from ftkin.calibration.imu_problem import ImuStaticProblem
from ftkin.calibration.imu_problem_base import NineChannelProblem
from ftkin.calibration.imu_samples import ImuSamples
from ftkin.cli import main
from ftkin.exceptions import InvalidInput, SuspectConvention
from ftkin.io.csv_table import write_csv
from tests.calibration.test_imu_fit import BIAS, IMU_ROTATION, SCALE, WRENCH_BIAS

G = 9.80665
MASS, COM = 1.7, np.array([0.01, -0.02, 0.08])  # [kg], [m, sensor frame]
NOISE = np.array([0.05] * 3 + [0.003] * 3)  # wrench per reading [N, N·m]
ACCEL_NOISE = 0.02  # [m/s²]
POSES = 16
ROTATION_COLUMNS = [f"r{i}{j}" for i in (1, 2, 3) for j in (1, 2, 3)]


def readings(per_pose: int, seed: int = 4):
    """``POSES`` orientations ``R_BS`` (a level base) and ``per_pose`` noisy readings of each: the
    load on the sensor (the tool's weight, ``-m g`` up, and its moment about the sensor origin,
    plus the bias) and the accelerometer's specific force (``+g`` up, in its own axes, scaled
    and biased)."""
    rng = np.random.default_rng(seed)
    rotations = Rotation.random(POSES, random_state=seed).as_matrix()
    ids = np.repeat(np.arange(POSES), per_pose)
    up = np.einsum("pji,j->pi", rotations, [0.0, 0.0, G])[ids]  # Rᵀ [0, 0, g], sensor frame
    weight = -MASS * up
    wrench = np.hstack([weight, np.cross(COM, weight)]) + WRENCH_BIAS
    wrench += rng.normal(0.0, 1.0, wrench.shape) * NOISE
    accel = (1.0 + SCALE) * (up @ IMU_ROTATION) + BIAS + rng.normal(0.0, ACCEL_NOISE, up.shape)
    return rotations[ids], ids, wrench, accel


@dataclass(frozen=True)
class Case:
    orientation: bool  # r11..r33 columns (the fused fit) or none (the IMU's)
    pose_column: bool
    per_pose: int  # readings per pose
    unit: str  # the accelerometer's, as logged

    def __str__(self):
        return (
            f"{'fused' if self.orientation else 'imu'}-"
            f"{'pose' if self.pose_column else 'nopose'}-{self.per_pose}x-{self.unit[0]}"
        )


CASES = [
    Case(orientation, pose_column, per_pose, unit)
    for orientation in (False, True)
    for pose_column in (True, False)
    for per_pose in (1, 4)
    for unit in ("g", "m/s^2")
]


def check_truth(mass: float, com) -> None:
    assert mass == pytest.approx(MASS, rel=0.005)
    np.testing.assert_allclose(com, COM, atol=1e-3)


@pytest.mark.parametrize("case", CASES, ids=str)
def test_every_shared_path_calibrates_through_the_cli(case, tmp_path, capsys):
    """The published shape among them: wrench with torques ``tx,ty,tz``, accelerometer in g,
    ``r11..r33``, one row per pose, no pose column (crashed with an AttributeError)."""
    rotations, ids, wrench, accel = readings(case.per_pose)
    logged = accel / G if case.unit == "g" else accel
    header = ["fx", "fy", "fz", "tx", "ty", "tz", "ax", "ay", "az"]
    columns = [wrench, logged]
    if case.orientation:
        header += ROTATION_COLUMNS
        columns.append(rotations.reshape(-1, 9))
    if case.pose_column:
        header = ["pose", *header]
        columns.insert(0, ids[:, None])
    path = tmp_path / "published.csv"
    write_csv(path, header, np.hstack(columns).tolist())
    out = tmp_path / "calib.json"
    flags = ["--accel-unit", "g"] if case.unit == "g" else []
    assert main(["calibrate", str(path), *flags, "-o", str(out)]) == 0, capsys.readouterr().err
    saved = json.loads(out.read_text())
    assert saved["method"] == ("fused" if case.orientation else "imu")
    assert saved["imu"].get("fused", False) is case.orientation
    check_truth(saved["tool_mass"], saved["center_of_mass"])
    np.testing.assert_allclose(saved["imu"]["accel_bias"], BIAS, atol=0.05)


@pytest.mark.parametrize("case", CASES, ids=str)
def test_every_shared_path_calibrates_through_the_api(case):
    rotations, ids, wrench, accel = readings(case.per_pose)
    logged = accel / G if case.unit == "g" else accel
    pose_ids = ids if case.pose_column else None
    if case.orientation:
        samples = Samples.from_rotations(rotations, wrench, pose_ids)
        samples = FusedSamples.from_arrays(samples, logged, accel_unit=case.unit)
    else:
        samples = ImuSamples.from_arrays(logged, wrench, pose_ids, accel_unit=case.unit)
    result = ftkin.calibrate(samples)
    assert result.method == ("fused" if case.orientation else "imu")
    check_truth(result.tool_mass, result.center_of_mass)
    np.testing.assert_allclose(result.accel_bias, BIAS, atol=0.05)


# ---------------------------------------------------------------- the interface both declare
def _problems(rng):
    """An IMU problem and a fused one on the same poses, at a slower IMU's count factor."""
    rotations = Rotation.random(6, random_state=1).as_matrix()
    accel = rng.normal(0.0, 5.0, (6, 3))
    wrenches = rng.normal(0.0, 5.0, (6, 6))
    counts, noise = np.full(6, 4.0), np.linspace(0.01, 0.09, 9)
    units = accel / np.linalg.norm(accel, axis=1)[:, None]
    imu = ImuStaticProblem(accel, wrenches, counts, noise, G, IMU_ROTATION, units, True, (), 0.25)
    fused = FusedStaticProblem(
        rotations,
        accel,
        wrenches,
        counts,
        noise,
        G,
        np.eye(3),
        IMU_ROTATION,
        "none",
        True,
        (),
        0.25,
    )
    return imu, fused


def test_both_problems_whiten_by_the_independent_readings(rng):
    """``sqrt(n_ic) / σ_c``, the accelerometer's ``n`` times the count factor, for either
    problem (the fused one had no factor: a slower IMU was weighed by the rows it was spread
    over)."""
    expected = np.sqrt(4.0 * np.repeat([0.25, 1.0], [3, 6])) / np.linspace(0.01, 0.09, 9)
    for problem in _problems(rng):
        assert isinstance(problem, NineChannelProblem)
        np.testing.assert_allclose(problem.weights, np.tile(expected, (6, 1)), rtol=1e-12)
        x = np.zeros(problem.parameter_count)
        x[0:3] = [0.0, 0.0, -15.0] if isinstance(problem, FusedStaticProblem) else x[0:3]
        x[6] = 1.5 if isinstance(problem, ImuStaticProblem) else x[6]
        np.testing.assert_allclose(
            problem.whitened_residuals(x), (problem.residuals(x) * expected).ravel(), rtol=1e-12
        )
        assert covariance_at(problem, x, 3, "").shape == (problem.parameter_count,) * 2


def test_a_problem_missing_a_member_fails_where_it_is_declared():
    with pytest.raises(TypeError, match="accel_count_factor"):

        @dataclass(frozen=True)
        class Forgetful(NineChannelProblem):  # noqa: F841 (defining it is the test)
            accel: np.ndarray
            wrenches: np.ndarray
            counts: np.ndarray
            noise: np.ndarray
            g: float
            scale_free: tuple = ()

    @dataclass(frozen=True)
    class NoModel(NineChannelProblem):
        accel: np.ndarray
        wrenches: np.ndarray
        counts: np.ndarray
        noise: np.ndarray
        g: float
        scale_free: tuple = ()
        accel_count_factor: float = 1.0

    with pytest.raises(TypeError, match="abstract"):
        NoModel(np.zeros((1, 3)), np.zeros((1, 6)), np.ones(1), np.ones(9), G)


def test_too_many_poses_advise_what_each_door_takes(tmp_path, capsys):
    """Beyond MAX_POSES ungrouped rows: the message names the command line's pose column, time
    column and --dynamic, and the API's pose_ids and calibrate_dynamic (no keyword a flag user
    cannot give, no flag an API user cannot)."""
    from ftkin.calibration.imu_fit import MAX_POSES

    rotations = Rotation.random(MAX_POSES + 1, random_state=2).as_matrix()
    up = np.einsum("pji,j->pi", rotations, [0.0, 0.0, G])
    wrench = np.hstack([-MASS * up, np.cross(COM, -MASS * up)])
    accel = up @ IMU_ROTATION
    with pytest.raises(InvalidInput, match="pose_ids in Python") as caught:
        ftkin.calibrate(ImuSamples.from_arrays(accel, wrench))
    assert "ftkin.calibrate_dynamic" in str(caught.value)
    path = tmp_path / "rows.csv"
    write_csv(
        path, ["fx", "fy", "fz", "mx", "my", "mz", "ax", "ay", "az"], np.hstack([wrench, accel])
    )
    assert main(["calibrate", str(path)]) == 2
    err = capsys.readouterr().err
    assert "'pose' column" in err and "--dynamic" in err and "Traceback" not in err


def test_a_joined_slower_imu_is_counted_in_the_fused_fit_too(tmp_path):
    """Wrench at 500 Hz, IMU at 100 Hz and an orientation log, joined: the fused samples keep the
    accelerometer's count factor (the rate ratio times 2/3: linear interpolation), and the fused
    problem weighs the accelerometer by it."""
    from ftkin.calibration.fused_fit import fit_fused_static
    from ftkin.calibration.fused_options import FusedCalibrationOptions
    from ftkin.io import load_imu_samples

    rotations, _, _, _ = readings(1)
    hold = 2.0  # [s] per pose, still
    t_wrench, t_imu = np.arange(0.0, POSES * hold, 1 / 500), np.arange(0.0, POSES * hold, 1 / 100)
    pose_of = lambda t: np.minimum((t // hold).astype(int), POSES - 1)  # noqa: E731
    up = np.einsum("pji,j->pi", rotations, [0.0, 0.0, G])
    rng = np.random.default_rng(9)
    weight = -MASS * up[pose_of(t_wrench)]
    wrench = np.hstack([weight, np.cross(COM, weight)]) + WRENCH_BIAS
    wrench += rng.normal(0.0, 1.0, wrench.shape) * NOISE
    accel = up[pose_of(t_imu)] @ IMU_ROTATION + BIAS + rng.normal(0.0, ACCEL_NOISE, (len(t_imu), 3))
    quaternions = Rotation.from_matrix(rotations[pose_of(t_imu)]).as_quat()[:, [3, 0, 1, 2]]
    files = []
    for name, header, values in (
        ("wrench", ["t", "fx", "fy", "fz", "mx", "my", "mz"], np.column_stack([t_wrench, wrench])),
        ("imu", ["t", "ax", "ay", "az"], np.column_stack([t_imu + 1e-4, accel])),
        ("pose", ["t", "qw", "qx", "qy", "qz"], np.column_stack([t_imu + 2e-4, quaternions])),
    ):
        files.append(tmp_path / f"{name}.csv")
        write_csv(files[-1], header, values.tolist())
    samples, _ = load_imu_samples(*files)
    factor = (100.0 / 500.0) * 2.0 / 3.0
    assert samples.accel_count_factor == pytest.approx(factor, rel=1e-3)
    assert samples.imu.accel_count_factor == pytest.approx(factor, rel=1e-3)
    fit = fit_fused_static(samples.pose_averages(), G, FusedCalibrationOptions(), "none")
    counts = fit.problem.counts[:, None]
    np.testing.assert_allclose(
        fit.problem.channel_counts[:, :3], np.tile(factor * counts, 3), rtol=1e-3
    )
    np.testing.assert_allclose(fit.problem.channel_counts[:, 3:], np.tile(counts, 6), rtol=1e-12)


def test_a_reaction_wrench_from_the_imu_alone_is_named_and_the_fix_works(tmp_path, capsys):
    """The IMU's fit takes no sensor sign: ``--sensor-sign -1`` was accepted and ignored; it is
    refused, and the fix both doors are given (negate the wrench columns) calibrates."""
    _, ids, wrench, accel = readings(4)
    with pytest.raises(SuspectConvention) as caught:
        ftkin.calibrate(ImuSamples.from_arrays(accel, -wrench, ids))
    assert "negate the wrench (fx..mz)" in caught.value.fixes
    header = ["pose", "fx", "fy", "fz", "mx", "my", "mz", "ax", "ay", "az"]
    reaction = tmp_path / "reaction.csv"
    write_csv(reaction, header, np.column_stack([ids, -wrench, accel]).tolist())
    assert main(["calibrate", str(reaction), "--sensor-sign", "-1"]) == 2
    err = capsys.readouterr().err
    assert "negate the wrench columns (fx..mz)" in err and "Traceback" not in err
    negated = tmp_path / "negated.csv"  # the advice followed
    write_csv(negated, header, np.column_stack([ids, wrench, accel]).tolist())
    out = tmp_path / "calib.json"
    assert main(["calibrate", str(negated), "-o", str(out)]) == 0
    saved = json.loads(out.read_text())
    check_truth(saved["tool_mass"], saved["center_of_mass"])


def test_a_fused_calibration_of_a_reaction_sensor_compensates_with_the_imu():
    """A fused calibration made with ``sensor_sign=-1`` stores the sign; the IMU's compensator
    ignored it (35 N of contact where there is none). Every path of it now reads the raw
    reading times the stored signs: with no contact, the contact is the noise."""
    from ftkin.control import ImuCompensator

    rotations, ids, wrench, accel = readings(4)
    calibration = ftkin.calibrate(
        FusedSamples.from_arrays(Samples.from_rotations(rotations, -wrench, ids), accel),
        sensor_sign=-1,
    )
    assert calibration.sensor_sign == -1
    compensator = ImuCompensator(calibration)
    batch = compensator.compensate_batch(-wrench, accel)
    single = np.array([compensator.compensate(w, a) for w, a in zip(-wrench, accel)])
    still = np.zeros(3)
    moving = np.array(
        [compensator.compensate_moving(w, a, still, still) for w, a in zip(-wrench, accel)]
    )
    floats = np.array(
        [compensator.contact_floats(list(w), list(a)) for w, a in zip(-wrench, accel)]
    )
    for contact in (batch, single, moving, floats):
        assert np.median(np.linalg.norm(contact[:, :3], axis=1)) < 3 * NOISE[0]
        assert np.median(np.linalg.norm(contact[:, 3:], axis=1)) < 3 * NOISE[3]
    np.testing.assert_allclose(single, batch, atol=1e-9)
