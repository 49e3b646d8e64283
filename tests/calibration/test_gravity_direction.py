"""A tool weight far from the expected gravity direction is warned (5°), and refused beyond 15°
from a declared one (issue 37 item 7).

The readings come from a statics computation independent of ftkin's model: scipy's rotations,
the weight ``m g`` turned by a known tilt, ``f = R_BSᵀ w`` and ``τ = c × f`` by numpy, plus a
bias and seeded noise. The angle the data carry is the tilt by construction; the noise moves the
fitted direction by about 0.01°, far inside the 1° margins of the cases below.
"""

from __future__ import annotations

import logging

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import ftkin
from ftkin import Samples, calibrate
from ftkin.cli import main
from ftkin.exceptions import SuspectConvention
from ftkin.io.csv_table import write_csv

MASS = 0.8  # kg
COM = np.array([0.01, -0.02, 0.06])  # m, sensor frame
BIAS = np.array([1.0, -0.5, 0.3, 0.02, -0.01, 0.005])  # N, N·m
G = 9.80665  # m/s²
NOISE = np.array([0.01, 0.01, 0.01, 0.001, 0.001, 0.001])  # N, N·m per reading


def tilted_down(tilt_deg: float, azimuth_deg: float = 30.0) -> np.ndarray:
    """Unit vector [base frame] ``tilt_deg`` away from base −z, towards ``azimuth_deg``."""
    axis = Rotation.from_euler("z", azimuth_deg, degrees=True).apply([1.0, 0.0, 0.0])
    return Rotation.from_rotvec(np.deg2rad(tilt_deg) * axis).apply([0.0, 0.0, -1.0])


def statics(tilt_deg: float, count: int = 24, seed: int = 0):
    """Orientations ``R_BS`` ``(N, 3, 3)`` and readings ``(N, 6)`` [N, N·m] of the tool under
    gravity ``tilt_deg`` from base −z (independent of ftkin's model)."""
    rng = np.random.default_rng(seed)
    rotations = Rotation.random(count, random_state=seed).as_matrix()
    weight = MASS * G * tilted_down(tilt_deg)
    forces = np.einsum("nji,j->ni", rotations, weight)  # R_BSᵀ w
    torques = np.cross(COM, forces)
    wrenches = np.hstack([forces, torques]) + BIAS + rng.normal(scale=NOISE, size=(count, 6))
    return rotations, wrenches


def tilt_warnings(caplog) -> list[str]:
    return [r.getMessage() for r in caplog.records if "away from the expected gravity" in r.message]


@pytest.mark.parametrize("tilt_deg", [3.0, 6.0, 14.0, 16.0, 80.0])
def test_undeclared_floor_warns_beyond_5_degrees_and_never_refuses(tilt_deg, caplog):
    rotations, wrenches = statics(tilt_deg)
    with caplog.at_level(logging.WARNING):
        result = calibrate(Samples.from_rotations(rotations, wrenches))
    np.testing.assert_allclose(result.tool_mass, MASS, rtol=2e-3)
    np.testing.assert_allclose(result.center_of_mass, COM, atol=1e-3)
    warned = tilt_warnings(caplog)
    if tilt_deg < 5.0:
        assert warned == []
        assert not any("expected gravity" in w for w in result.diagnostics.warnings)
    else:
        assert len(warned) == 1
        assert f"{tilt_deg:.1f}° away" in warned[0]  # the angle, the causes and the flags
        assert "another frame than the robot base" in warned[0]
        assert "--expected-gravity" in warned[0] and "--base-mount wall" in warned[0]
        assert "default floor mount" in warned[0]
        assert warned[0] in result.diagnostics.warnings  # kept in the calibration file


@pytest.mark.parametrize("tilt_deg", [3.0, 6.0, 14.0, 16.0, 80.0])
@pytest.mark.parametrize(
    "declared", [{"base_mount": "floor"}, {"expected_gravity": [0.0, 0.0, -2.0]}]
)
def test_declared_direction_refuses_beyond_15_degrees(tilt_deg, declared, caplog):
    rotations, wrenches = statics(tilt_deg)
    samples = Samples.from_rotations(rotations, wrenches)
    if tilt_deg > 15.0:
        with pytest.raises(SuspectConvention, match="--allow-tilt") as info:
            calibrate(samples, **declared)
        assert f"{tilt_deg:.1f}° away" in str(info.value)
        assert "--allow-tilt" in info.value.fixes
        with caplog.at_level(logging.WARNING):  # the override named in the refusal works
            result = calibrate(samples, allow_tilt=True, **declared)
        assert len(tilt_warnings(caplog)) == 1  # still said
    else:
        with caplog.at_level(logging.WARNING):
            result = calibrate(samples, **declared)
        assert len(tilt_warnings(caplog)) == (tilt_deg > 5.0)
    np.testing.assert_allclose(result.tool_mass, MASS, rtol=2e-3)


@pytest.mark.parametrize("declared", [{}, {"base_mount": "floor"}, {"allow_tilt": True}])
def test_100_degrees_is_a_reversed_sign_whatever_is_declared(declared):
    rotations, wrenches = statics(100.0)
    with pytest.raises(SuspectConvention, match="--sensor-sign -1"):
        calibrate(Samples.from_rotations(rotations, wrenches), **declared)


def test_the_true_direction_declared_is_not_warned(caplog):
    rotations, wrenches = statics(80.0)
    with caplog.at_level(logging.WARNING):  # the advice followed: gravity where it is
        result = calibrate(
            Samples.from_rotations(rotations, wrenches), expected_gravity=tilted_down(80.0)
        )
    assert tilt_warnings(caplog) == []
    np.testing.assert_allclose(result.tool_mass, MASS, rtol=2e-3)
    with caplog.at_level(logging.WARNING):  # or no direction at all
        calibrate(Samples.from_rotations(rotations, wrenches), base_mount="wall")
    assert tilt_warnings(caplog) == []


def test_linear_method_warns_the_same(caplog):
    rotations, wrenches = statics(80.0)
    with caplog.at_level(logging.WARNING):
        calibrate(Samples.from_rotations(rotations, wrenches), method="linear")
    assert len(tilt_warnings(caplog)) == 1
    with pytest.raises(SuspectConvention, match="--allow-tilt"):
        calibrate(Samples.from_rotations(rotations, wrenches), method="linear", base_mount="floor")


def _csv(tmp_path, tilt_deg: float):
    rotations, wrenches = statics(tilt_deg)
    quaternions = Rotation.from_matrix(rotations).as_quat(scalar_first=True)
    return write_csv(
        tmp_path / f"tilt{tilt_deg:g}.csv",
        ["qw", "qx", "qy", "qz", "fx", "fy", "fz", "mx", "my", "mz"],
        np.hstack([quaternions, wrenches]).tolist(),
    )


def test_cli_prints_the_warning_refuses_when_declared_and_doctor_names_it(tmp_path, capsys):
    path = _csv(tmp_path, 80.0)
    assert main(["calibrate", str(path)]) == 0
    out = capsys.readouterr().out
    assert "80.0° away from the expected gravity direction" in out
    output = tmp_path / "c.json"
    assert main(["calibrate", str(path), "--base-mount", "floor", "-o", str(output)]) == 2
    err = capsys.readouterr().err
    assert "80.0° away" in err and "--allow-tilt" in err and "Traceback" not in err
    assert not output.exists()
    args = ["calibrate", str(path), "--base-mount", "floor", "--allow-tilt", "-o", str(output)]
    assert main(args) == 0
    capsys.readouterr()
    assert abs(ftkin.load_calibration(output).tool_mass - MASS) < 2e-3
    direction = [f"{v:.6f}" for v in tilted_down(80.0)]
    assert main(["calibrate", str(path), "--expected-gravity", *direction]) == 0
    assert "expected gravity direction" not in capsys.readouterr().out
    assert main(["doctor", str(path)]) == 0
    out = capsys.readouterr().out
    assert "verdict: suspect" in out and "80.0° away" in out
    assert main(["doctor", str(_csv(tmp_path, 3.0))]) == 0
    assert "verdict: ok" in capsys.readouterr().out
