"""A calibration that explains almost none of its readings' variation is refused (issue 37
item 9); the doctor tries the column mix-ups.

The threshold (:data:`~ftkin.calibration.explained.MIN_EXPLAINED`, 0.5) is tested on both sides
with residuals built by hand, and end to end with readings from a statics computation
independent of ftkin's model, whose share explained by the true tool is computed here from the
noise drawn.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from ftkin import Samples, SensorNoise, calibrate
from ftkin.calibration.explained import MIN_EXPLAINED, check_explained, explained_share
from ftkin.calibration.fit_quality import FIT_ALPHA
from ftkin.exceptions import UnexplainedReadings
from ftkin.io import diagnose_samples
from ftkin.io.csv_table import write_csv

G = 9.80665  # m/s²
COM = np.array([0.01, 0.02, 0.05])  # m
BIAS = np.array([0.5, -0.2, 0.1, 0.01, -0.02, 0.003])  # N, N·m


def statics(mass, noise, count=40, repeats=1, seed=3):
    """``(R_BS (N,3,3), wrenches (N,6), noise drawn (N,6), pose ids)`` of a tool of ``mass`` [kg]
    at ``count`` random orientations, ``repeats`` readings each; ``noise``: (force [N],
    torque [N·m]) standard deviations."""
    rng = np.random.default_rng(seed)
    rotations = np.repeat(Rotation.random(count, random_state=seed).as_matrix(), repeats, 0)
    forces = np.einsum("nji,j->ni", rotations, [0.0, 0.0, -mass * G])
    drawn = rng.normal(size=(len(rotations), 6)) * np.repeat(noise, 3)
    wrenches = np.hstack([forces, np.cross(COM, forces)]) + BIAS + drawn
    return rotations, wrenches, drawn, np.repeat(np.arange(count), repeats)


def _result(share: float, noise_source=None, p_value=np.nan):
    """A result-like record whose readings vary by 4 (N²) in fx and whose residuals leave
    ``1 − share`` of it."""
    wrenches = np.zeros((4, 6))
    wrenches[:, 0] = [1.0, -1.0, 1.0, -1.0]  # Σ (w − w̄)² = 4
    residuals = np.zeros((4, 6))
    residuals[:, 0] = np.sqrt(1.0 - share) * np.array([1.0, -1.0, 1.0, -1.0])
    diagnostics = (
        None
        if noise_source is None
        else SimpleNamespace(noise_source=noise_source, fit_ok=not (p_value < FIT_ALPHA))
    )
    return SimpleNamespace(
        pose_wrenches=wrenches, residuals=residuals, diagnostics=diagnostics, tool_weight=0.01
    )


@pytest.mark.parametrize("share", [0.0, 0.3, 0.49, 0.51, 0.7, 1.0])
def test_the_threshold_on_both_sides_by_hand(share):
    result = _result(share)
    np.testing.assert_allclose(
        explained_share(result.pose_wrenches, result.residuals), share, atol=1e-12
    )
    if share < MIN_EXPLAINED:
        with pytest.raises(UnexplainedReadings, match="explains .* of the readings' variation"):
            check_explained(result)
    else:
        check_explained(result)


def test_readings_within_a_noise_known_on_its_own_are_not_refused():
    check_explained(_result(0.2, "spread", p_value=0.4))  # nothing beyond the noise
    check_explained(_result(0.2, "given", p_value=0.4))
    with pytest.raises(UnexplainedReadings):  # beyond it
        check_explained(_result(0.2, "spread", p_value=1e-9))
    with pytest.raises(UnexplainedReadings):  # the noise taken from the same residuals
        check_explained(_result(0.2, "residuals"))


@pytest.mark.parametrize(
    ("mass", "low", "high", "refused"),
    [(0.0065, 0.15, 0.4, True), (0.016, 0.6, 0.9, False)],  # kg; the true share's range
)
def test_a_tool_lighter_than_the_noise_is_refused_and_a_heavier_one_kept(mass, low, high, refused):
    noise = (0.05, 0.001)  # N, N·m
    rotations, wrenches, drawn, _ = statics(mass, noise)
    truth_share = 1.0 - np.sum(drawn**2) / np.sum((wrenches - wrenches.mean(0)) ** 2)
    assert low < truth_share < high  # the case is on the side it is meant to be
    samples = Samples.from_rotations(rotations, wrenches)
    if refused:
        with pytest.raises(UnexplainedReadings) as info:
            calibrate(samples)
        assert info.value.explained < MIN_EXPLAINED and info.value.threshold == MIN_EXPLAINED
    else:
        result = calibrate(samples)
        assert explained_share(result.pose_wrenches, result.residuals) >= MIN_EXPLAINED


def test_a_sensor_without_tool_with_repeated_readings_is_not_refused():
    noise = (0.05, 0.001)
    rotations, wrenches, _, pose_ids = statics(0.0, noise, count=20, repeats=5)
    result = calibrate(
        Samples.from_rotations(rotations, wrenches, pose_ids),
        noise=SensorNoise([0.05] * 3, [0.001] * 3),
    )
    np.testing.assert_allclose(result.force_offset, BIAS[:3], atol=0.02)


@pytest.mark.parametrize("declared", [{}, {"base_mount": "floor"}, {"method": "linear"}])
def test_swapped_force_and_torque_columns_are_refused_not_saved(declared):
    rotations, wrenches, _, _ = statics(0.8, (0.01, 0.001))
    swapped = wrenches[:, [3, 4, 5, 0, 1, 2]]
    with pytest.raises(UnexplainedReadings, match="ftkin doctor") as info:
        calibrate(Samples.from_rotations(rotations, swapped), **declared)
    assert info.value.explained < 0.2


@pytest.mark.parametrize(
    ("name", "order"),
    [
        ("force and torque columns swapped", [3, 4, 5, 0, 1, 2]),
        ("the columns in the order fx,mx,fy,my,fz,mz", [0, 3, 1, 4, 2, 5]),
    ],
)
def test_doctor_names_the_column_mix_ups(name, order, tmp_path):
    rotations, wrenches, _, _ = statics(0.8, (0.01, 0.001), count=16)
    quaternions = Rotation.from_matrix(rotations).as_quat(scalar_first=True)
    path = write_csv(
        tmp_path / "mixed.csv",
        ["qw", "qx", "qy", "qz", "fx", "fy", "fz", "mx", "my", "mz"],
        np.hstack([quaternions, wrenches[:, order]]),
    )
    report = diagnose_samples(path)
    assert report.verdict == "mistake" and report.culprit.reading.name == name
    np.testing.assert_allclose(report.culprit.model.tool_weight, 0.8 * G, rtol=1e-2)
