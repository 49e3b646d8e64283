"""Every piece of advice ``ftkin calibrate`` and ``ftkin doctor`` print works when followed
(issue 37 item 9).

Each case writes a samples file with one mistake, runs ``ftkin calibrate``, checks that the
advice printed is the expected one, does what it says (edits the file or adds the flag), and
runs ``ftkin calibrate`` again: it must succeed with the tool the readings were made from. The
readings come from a statics computation independent of ftkin's model (scipy rotations, numpy
``f = R_BSᵀ m g``, ``τ = c × f``); the joint-angle case takes ``R_BS`` from the bundled arm's
forward kinematics (the arm, not the wrench model).
"""

from __future__ import annotations

import json
import re

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from ftkin.cli import main
from ftkin.io.csv_table import read_table, write_csv

MASS = 0.6  # kg
COM = np.array([0.02, -0.01, 0.07])  # m, sensor frame
BIAS = np.array([0.9, -0.4, 0.25, 0.015, -0.02, 0.008])  # N, N·m
G = 9.80665  # m/s²
NOISE = np.array([0.01, 0.01, 0.01, 0.001, 0.001, 0.001])  # N, N·m per reading
WRENCH = ["fx", "fy", "fz", "mx", "my", "mz"]
QUATERNION = ["qw", "qx", "qy", "qz"]


def statics(rotations, down=(0.0, 0.0, -1.0), seed=2):
    """Readings ``(N, 6)`` [N, N·m] of the tool at ``R_BS`` ``(N, 3, 3)``, gravity along
    ``down`` [base frame]."""
    rng = np.random.default_rng(seed)
    forces = np.einsum("nji,j->ni", rotations, MASS * G * np.asarray(down))  # R_BSᵀ w
    wrenches = np.hstack([forces, np.cross(COM, forces)]) + BIAS
    return wrenches + rng.normal(scale=NOISE, size=wrenches.shape)


ROTATION = Rotation.random(16, random_state=4)
R_BS = ROTATION.as_matrix()
Q = ROTATION.as_quat(scalar_first=True)  # w, x, y, z


def _rotate(wrenches, rotations):
    """Force and torque each by ``rotations`` (``(N, 3, 3)``)."""
    force = np.einsum("nij,nj->ni", rotations, wrenches[:, :3])
    return np.hstack([force, np.einsum("nij,nj->ni", rotations, wrenches[:, 3:])])


def _with_columns(path, new_path, change):
    """A copy of the CSV ``path`` with ``change(header, values) -> (header, values)`` applied."""
    table = read_table(path)
    header, values = change(list(table.header), table.floats(table.header))
    return write_csv(new_path, header, values)


def _scale(names, factor):
    def change(header, values):
        values = values.copy()
        for name in names:
            values[:, header.index(name)] *= factor
        return header, values

    return change


def _renamed(mapping):
    return lambda header, values: ([mapping.get(name, name) for name in header], values)


def _renames_from_advice(text):
    """The renames the advice lists: 'the column named A holds B, C holds D, ...'."""
    listed = re.search(r"the column named ((?:\w+ holds \w+(?:, )?)+)", text)[1]
    return dict(pair.split(" holds ") for pair in listed.split(", "))


def _rotate_back(header, values):
    rotations = Rotation.from_quat(values[:, :4], scalar_first=True).as_matrix()
    wrenches = _rotate(values[:, 4:], np.transpose(rotations, (0, 2, 1)))  # R_BSᵀ
    return header, np.hstack([values[:, :4], wrenches])


def _quaternion_file(rotations_q, wrenches, header=None):
    return (header or [*QUATERNION, *WRENCH]), np.hstack([rotations_q, wrenches])


def _euler_radians():
    euler = ROTATION.as_euler("ZYX")  # R = Rz(alpha) Ry(beta) Rx(gamma), radians
    return ["alpha", "beta", "gamma", *WRENCH], np.hstack([euler, statics(R_BS)])


def _matrix_transposed():
    entries = np.transpose(R_BS, (0, 2, 1)).reshape(-1, 9)  # R_SB row-major under rIJ
    names = [f"r{i}{j}" for i in (1, 2, 3) for j in (1, 2, 3)]
    return [*names, *WRENCH], np.hstack([entries, statics(R_BS)])


def _swap_rIJ(header, values):
    return [re.sub(r"^r(\d)(\d)$", r"r\2\1", name) for name in header], values


# name: (the file with the mistake, the advice expected, how to follow it: (file edit, flags))
CASES = {
    "euler in radians": (
        _euler_radians,
        "give alpha, beta, gamma in degrees (multiply by 180/π",
        (_scale(["alpha", "beta", "gamma"], 180 / np.pi), []),
    ),
    "quaternion x,y,z,w": (
        lambda: _quaternion_file(Q[:, [1, 2, 3, 0]], statics(R_BS)),
        "name the columns qx,qy,qz,qw",
        (_renamed({"qw": "qx", "qx": "qy", "qy": "qz", "qz": "qw"}), []),
    ),
    "orientation inverted": (
        lambda: _quaternion_file(Q * [1, -1, -1, -1], statics(R_BS)),
        "negate qx,qy,qz",
        (_scale(["qx", "qy", "qz"], -1.0), []),
    ),
    "matrix transposed": (_matrix_transposed, "swap rIJ and rJI", (_swap_rIJ, [])),
    "wrench in the base frame": (
        lambda: _quaternion_file(Q, _rotate(statics(R_BS), R_BS)),
        "rotate it by R_BS^T",
        (_rotate_back, []),
    ),
    "reaction": (
        lambda: _quaternion_file(Q, -statics(R_BS)),
        "--sensor-sign -1",
        (None, ["--sensor-sign", "-1"]),
    ),
    "ceiling": (
        lambda: _quaternion_file(Q, statics(R_BS, down=(0.0, 0.0, 1.0))),
        "--base-mount ceiling",
        (None, ["--base-mount", "ceiling"]),
    ),
    "torques in N·mm": (
        lambda: _quaternion_file(Q, statics(R_BS) * [1, 1, 1, 1e3, 1e3, 1e3]),
        "divide mx, my, mz by 1000",
        (_scale(["mx", "my", "mz"], 1e-3), []),
    ),
    "sensor turned about x": (
        lambda: _quaternion_file(Q, statics(R_BS) * [1, -1, -1, 1, -1, -1]),
        "negate the columns fy, fz, my, mz",
        (_scale(["fy", "fz", "my", "mz"], -1.0), []),
    ),
    "x axis reversed": (
        lambda: _quaternion_file(Q, statics(R_BS) * [-1, 1, 1, -1, 1, 1]),
        "--flip-axis x",
        (None, ["--flip-axis", "x"]),
    ),
    "forces and torques swapped": (
        lambda: _quaternion_file(Q, statics(R_BS)[:, [3, 4, 5, 0, 1, 2]]),
        "rename them in the header",
        ("renames", []),
    ),
    "columns interleaved": (
        lambda: _quaternion_file(Q, statics(R_BS)[:, [0, 3, 1, 4, 2, 5]]),
        "rename them in the header",
        ("renames", []),
    ),
    "header interleaved": (
        lambda: _quaternion_file(
            Q, statics(R_BS), [*QUATERNION, "fx", "mx", "fy", "my", "fz", "mz"]
        ),
        "rename them in the header",
        ("renames", []),
    ),
    "tilted 80° (floor not declared)": (
        lambda: _quaternion_file(Q, statics(R_BS, down=[0.0, np.sin(1.3963), -np.cos(1.3963)])),
        "--expected-gravity GX GY GZ",
        (None, ["--expected-gravity", "0", f"{np.sin(1.3963):.9f}", f"{-np.cos(1.3963):.9f}"]),
    ),
}


def _run(args, capsys, caplog) -> tuple[int, str]:
    code = main(args)
    captured = capsys.readouterr()
    text = captured.out + captured.err + caplog.text
    caplog.clear()
    return code, text


def _check_tool(path):
    stored = json.loads(path.read_text())
    mass = np.linalg.norm(stored["gravity_in_base"]) / stored["g"]
    np.testing.assert_allclose(mass, MASS, rtol=5e-3)
    np.testing.assert_allclose(stored["center_of_mass"], COM, atol=2e-3)


@pytest.mark.parametrize("case", list(CASES))
def test_the_advice_printed_works_when_followed(case, tmp_path, capsys, caplog):
    make, advice, (edit, flags) = CASES[case]
    header, values = make()
    path = write_csv(tmp_path / "mistake.csv", header, values)
    output = tmp_path / "calibration.json"
    code, text = _run(["calibrate", str(path), "-o", str(output)], capsys, caplog)
    assert advice in text, text
    if code == 0:  # a suspicion, warned: the calibration written is not the tool
        stored = json.loads(output.read_text())
        assert case.startswith("tilted") or abs(np.linalg.norm(stored["center_of_mass"])) > 0.1
        output.unlink()
    if edit == "renames":
        edit = _renamed(_renames_from_advice(text))
    fixed = path if edit is None else _with_columns(path, tmp_path / "fixed.csv", edit)
    code, text = _run(["calibrate", str(fixed), *flags, "-o", str(output)], capsys, caplog)
    assert code == 0, text
    assert "WARNING" not in text and "expected gravity" not in text, text
    _check_tool(output)


def test_a_declared_tilt_refused_is_accepted_as_the_refusal_says(tmp_path, capsys, caplog):
    header, values = CASES["tilted 80° (floor not declared)"][0]()
    path = write_csv(tmp_path / "tilted.csv", header, values)
    output = tmp_path / "calibration.json"
    args = ["calibrate", str(path), "--base-mount", "floor", "-o", str(output)]
    code, text = _run(args, capsys, caplog)
    assert code == 2 and "--allow-tilt" in text and not output.exists()
    code, text = _run([*args, "--allow-tilt"], capsys, caplog)
    assert code == 0
    _check_tool(output)
    for flags in (["--base-mount", "wall"], CASES["tilted 80° (floor not declared)"][2][1]):
        code, text = _run(["calibrate", str(path), *flags, "-o", str(output)], capsys, caplog)
        assert code == 0 and "expected gravity" not in text, text


def test_an_unexplained_fit_sends_to_the_doctor_whose_advice_works(tmp_path, capsys, caplog):
    header, values = CASES["forces and torques swapped"][0]()
    path = write_csv(tmp_path / "swapped.csv", header, values)
    output = tmp_path / "calibration.json"
    args = ["calibrate", str(path), "--no-convention-check", "-o", str(output)]
    code, text = _run(args, capsys, caplog)
    assert code == 2 and "explains" in text and "ftkin doctor" in text and not output.exists()
    code, text = _run(["doctor", str(path)], capsys, caplog)
    assert code == 1 and "verdict: mistake" in text and "force and torque columns swapped" in text
    fixed = _with_columns(path, tmp_path / "fixed.csv", _renamed(_renames_from_advice(text)))
    code, text = _run(["calibrate", str(fixed), "-o", str(output)], capsys, caplog)
    assert code == 0, text
    _check_tool(output)
