"""What a file declares wins; a doubt about it is a warning that says what it doubts (issue 37
item 8).

Readings from a statics computation independent of ftkin's model (scipy rotations, numpy
``f = R_BSᵀ m g``, ``τ = c × f``). The truth they were made from is the expectation.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from ftkin.cli import main
from ftkin.io import diagnose_samples
from ftkin.io.column_spelling import declared_wrench_units
from ftkin.io.csv_table import write_csv

G = 9.80665  # m/s²
BIAS = np.array([1.5, -0.7, 0.4, 0.03, -0.02, 0.01])  # N, N·m
WRENCH = ["fx", "fy", "fz", "mx", "my", "mz"]


def statics(mass, com, count=16, seed=1, noise=(0.0, 0.0)):
    """``(quaternions w,x,y,z, wrenches [N, N·m])`` of a tool under gravity along base −z."""
    rng = np.random.default_rng(seed)
    rotation = Rotation.random(count, random_state=seed)
    forces = rotation.inv().apply([0.0, 0.0, -mass * G])  # R_BSᵀ w
    torques = np.cross(com, forces)
    wrenches = np.hstack([forces, torques]) + BIAS
    wrenches += rng.normal(size=wrenches.shape) * np.repeat(noise, 3)
    return rotation.as_quat(scalar_first=True), wrenches


def write(path, quaternions, wrenches, header=WRENCH):
    return write_csv(path, ["qw", "qx", "qy", "qz", *header], np.hstack([quaternions, wrenches]))


def test_declared_wrench_units_reads_the_header_as_written():
    header = ["pose", "qw", "Fx (N)", "fy", "mx [N·m]", "Ty [N-mm]", "torque.z (lbf-in)", "t [ms]"]
    assert declared_wrench_units(header) == {
        "fx": "N",
        "mx": "N·m",
        "my": "N-mm",
        "mz": "lbf-in",
    }
    assert declared_wrench_units(["fx", "mx"]) == {}


def said(capsys, caplog) -> str:
    """What the command printed to stderr and logged (the CLI's log handler writes stderr)."""
    text = capsys.readouterr().err + caplog.text
    caplog.clear()
    return text


def test_a_peers_far_tool_with_declared_newton_metres_calibrates_and_warns(
    tmp_path, capsys, caplog
):
    """A 1 kg tool whose centre of mass is 3.7 m from the sensor, noise-free: the offsets come
    back to 1e-6 and the doubt is a warning naming the unit and the distance."""
    com = np.array([0.0, 0.0, 3.7])
    quaternions, wrenches = statics(1.0, com)
    header = [f"{name} [{'N' if name[0] == 'f' else 'N·m'}]" for name in WRENCH]
    path = write(tmp_path / "far.csv", quaternions, wrenches, header)
    output = tmp_path / "far.json"
    assert main(["calibrate", str(path), "-o", str(output)]) == 0
    err = said(capsys, caplog)
    assert "declares the torques in N·m" in err and "3.7 m from the sensor" in err
    assert "fit when read with" not in err  # no claim that another unit fits better
    stored = json.loads(output.read_text())
    np.testing.assert_allclose(stored["force_offset"], BIAS[:3], atol=1e-6)
    np.testing.assert_allclose(stored["torque_offset"], BIAS[3:], atol=1e-6)
    np.testing.assert_allclose(stored["center_of_mass"], com, atol=1e-6)


def test_undeclared_millimetres_are_still_refused_without_claiming_a_better_fit(
    tmp_path, capsys, caplog
):
    com = np.array([0.01, -0.02, 0.05])
    quaternions, wrenches = statics(0.5, com, noise=(0.01, 0.001))
    in_millimetres = wrenches * [1, 1, 1, 1e3, 1e3, 1e3]  # N·mm, header silent
    path = write(tmp_path / "nmm.csv", quaternions, in_millimetres)
    report = diagnose_samples(path)
    assert report.verdict == "mistake" and report.culprit.reading.name == "torques in N·mm"
    assert not report.by_fit  # it fits exactly as well as given (same residuals in N·mm)
    np.testing.assert_allclose(report.culprit.chi_square, report.fits[0].chi_square, rtol=1e-6)
    assert main(["calibrate", str(path)]) == 2
    err = said(capsys, caplog)
    assert "plausible only when read with torques in N·mm" in err
    assert "fits them no better" in err and "mx [N·mm]" in err
    # the advice followed: the unit declared in the header
    header = [f"{name} [N·mm]" if name[0] == "m" else name for name in WRENCH]
    fixed = write(tmp_path / "declared.csv", quaternions, in_millimetres, header)
    output = tmp_path / "declared.json"
    assert main(["calibrate", str(fixed), "-o", str(output)]) == 0
    capsys.readouterr()
    np.testing.assert_allclose(json.loads(output.read_text())["center_of_mass"], com, atol=2e-3)


@pytest.mark.parametrize("declared", ["N·m", "Nm"])
def test_declared_newton_metres_holding_millimetres_is_warned_not_accepted_silently(
    declared, tmp_path, capsys, caplog
):
    com = np.array([0.01, -0.02, 0.05])
    quaternions, wrenches = statics(0.5, com, noise=(0.01, 0.001))
    header = [f"{name} [{declared}]" if name[0] == "m" else name for name in WRENCH]
    path = write(tmp_path / "wrong.csv", quaternions, wrenches * [1, 1, 1, 1e3, 1e3, 1e3], header)
    assert main(["calibrate", str(path)]) == 0  # the declaration wins...
    err = said(capsys, caplog)
    # ...but the doubt is said: which unit, the distance it implies, the fix
    assert f"declares the torques in {declared}" in err
    distance = np.linalg.norm(com) * 1e3  # m, read as declared
    assert f"{distance:.3g} m from the sensor" in err and "declare N·mm" in err
    report = diagnose_samples(path)
    assert report.verdict == "suspect" and report.culprit is None
