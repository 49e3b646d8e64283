"""Convention mistakes are named, not fitted; clean data never trip the check.

Each mistake is simulated from a known truth on the bundled arm and on UR5 and
written the wrong way; the diagnosis must name exactly that mistake. Clean
sets (random arm, pose count, noise, tool, readings per pose, orientation
convention) must all come out "ok" (the benchmark bench_conventions.py runs
1,000 of them).
"""

from __future__ import annotations

import functools
import importlib.util
from pathlib import Path

import numpy as np
import pytest

import ftkin
from ftkin.cli import main
from ftkin.io.csv_table import Table, write_csv
from ftkin.io.table_readings import diagnose_table
from ftkin.kinematics.rotations import matrix_to_euler_zyx, matrix_to_quaternion

WRENCH = ["fx", "fy", "fz", "mx", "my", "mz"]
BENCH_CONVENTIONS = Path(__file__).parents[2] / "benchmarks" / "bench_conventions.py"
NOISE = np.array([0.02, 0.02, 0.02, 0.002, 0.002, 0.002])  # N, N·m per reading


@pytest.fixture(scope="module")
def arms(arm):
    from ftkin.kinematics.robots import load_robot

    return {"bundled": arm, "ur5": load_robot("ur5", [0.0, 0.0, 0.05])}


def _table(header, rows) -> Table:
    return Table(
        "sim.csv",
        list(header),
        [[repr(float(v)) for v in row] for row in rows],
        list(range(2, 2 + len(rows))),
        1,
    )


def _rotate(rotations, wrenches):
    """Sensor-frame wrenches expressed in the base frame (force and torque each by R_BS)."""
    return np.hstack(
        [
            np.einsum("nij,nj->ni", rotations, wrenches[:, :3]),
            np.einsum("nij,nj->ni", rotations, wrenches[:, 3:]),
        ]
    )


def _data(arm, rng, count=12):
    q = arm.random_configurations(count, rng, margin=0.3)
    rotations = arm.rotation_sensor_to_base(q)
    truth = ftkin.sim.sensor.paper_like_truth()
    return q, rotations, truth.predict(rotations) + rng.normal(scale=NOISE, size=(count, 6))


def _mistakes(arm, q, rotations, wrenches):
    joints = [f"q{i + 1}" for i in range(arm.nq)]
    euler = matrix_to_euler_zyx(rotations)  # rad
    quaternion = matrix_to_quaternion(rotations)  # w, x, y, z
    return {
        "Euler angles in radians": _table(
            ["alpha", "beta", "gamma", *WRENCH], np.hstack([euler, wrenches])
        ),
        "the quaternion as x,y,z,w": _table(
            ["qw", "qx", "qy", "qz", *WRENCH], np.hstack([quaternion[:, [1, 2, 3, 0]], wrenches])
        ),
        "the wrench in the base frame": _table(
            [*joints, *WRENCH], np.hstack([q, _rotate(rotations, wrenches)])
        ),
        "the readings negated (the reaction)": _table(
            [*joints, *WRENCH], np.hstack([q, -wrenches])
        ),
        "the sensor's x axis reversed": _table(
            [*joints, *WRENCH], np.hstack([q, wrenches * [-1, 1, 1, 1, -1, -1]])
        ),
        "the sensor's y axis reversed": _table(
            [*joints, *WRENCH], np.hstack([q, wrenches * [1, -1, 1, 1, -1, 1]])
        ),
        "the sensor's z axis reversed": _table(
            [*joints, *WRENCH], np.hstack([q, wrenches * [1, 1, -1, -1, -1, 1]])
        ),
        "joint angles in degrees": _table([*joints, *WRENCH], np.hstack([np.rad2deg(q), wrenches])),
        "torques in N·mm": _table(
            [*joints, *WRENCH], np.hstack([q, wrenches * [1, 1, 1, 1e3, 1e3, 1e3]])
        ),
    }


@pytest.mark.parametrize("arm_name", ["bundled", "ur5"])
def test_each_mistake_is_named(arms, arm_name):
    arm = arms[arm_name]
    rng = np.random.default_rng(2024)
    q, rotations, wrenches = _data(arm, rng)
    clean = _table([f"q{i + 1}" for i in range(arm.nq)] + WRENCH, np.hstack([q, wrenches]))
    assert diagnose_table(clean, arm).verdict == "ok"
    for expected, table in _mistakes(arm, q, rotations, wrenches).items():
        report = diagnose_table(table, arm)
        assert report.culprit is not None and report.culprit.reading.name == expected, (
            expected,
            report.reason,
        )
        # the reaction fits exactly as well as the given reading: only its gravity pointing up gives
        # it away
        assert report.verdict == ("suspect" if "reaction" in expected else "mistake"), expected


def test_the_fitted_alternative_recovers_the_truth(arm):
    """The reading that is named is not just a better fit: it gives back the simulated tool."""
    rng = np.random.default_rng(7)
    q, rotations, wrenches = _data(arm, rng, 15)
    table = _mistakes(arm, q, rotations, wrenches)["the quaternion as x,y,z,w"]
    report = diagnose_table(table, arm)
    truth = ftkin.sim.sensor.paper_like_truth()
    assert report.culprit.model.tool_weight == pytest.approx(truth.tool_weight, abs=0.02)
    np.testing.assert_allclose(report.culprit.model.center_of_mass, truth.center_of_mass, atol=2e-3)


def _clean_table(rng, arms):
    """A clean data set drawn at random (arm, tool, bias, tilt, poses, noise, repeats,
    convention) by ``benchmarks/bench_conventions.py``'s own ``draw`` and ``as_table``: the test
    checks the benchmark's no-false-alarm claim on the sets the benchmark draws.
    """
    bench = _bench_conventions()
    return bench.as_table(*bench.draw(rng, arms))


@functools.cache
def _bench_conventions():
    spec = importlib.util.spec_from_file_location("bench_conventions", BENCH_CONVENTIONS)
    bench = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(bench)
    return bench


def test_no_false_alarm_on_clean_sets(arms):
    rng = np.random.default_rng(12)
    alarms = []
    for k in range(300):
        arm, table = _clean_table(rng, arms)
        report = diagnose_table(table, arm)
        if report.verdict in ("mistake", "suspect"):
            alarms.append((k, report.verdict, report.message))
    assert alarms == []


def test_calibrate_refuses_and_doctor_explains(arm, tmp_path, capsys):
    rng = np.random.default_rng(3)
    q, rotations, wrenches = _data(arm, rng)
    euler = matrix_to_euler_zyx(rotations)  # radians under alpha, beta, gamma
    path = write_csv(
        tmp_path / "rad.csv",
        ["alpha", "beta", "gamma", *WRENCH],
        np.hstack([euler, wrenches]).tolist(),
    )
    assert main(["calibrate", str(path)]) == 2
    err = capsys.readouterr().err
    assert (
        "the data fit when read with Euler angles in radians" in err
        and "give alpha, beta, gamma in degrees" in err
    )
    with pytest.raises(ftkin.ConventionMistake) as info:
        from ftkin.cli.doctor import refuse_convention_mistakes

        refuse_convention_mistakes(ftkin.load_samples(path), None)
    assert info.value.reading == "Euler angles in radians"
    assert main(["doctor", str(path)]) == 1
    out = capsys.readouterr().out
    assert "verdict: mistake" in out and "Euler angles in radians" in out
    assert (
        main(["calibrate", str(path), "--no-convention-check", "--method", "linear"]) == 0
    )  # deliberate: fit as given
    capsys.readouterr()
    clean = write_csv(
        tmp_path / "ok.csv",
        ["alpha", "beta", "gamma", *WRENCH],
        np.hstack([np.rad2deg(euler), wrenches]).tolist(),
    )
    assert main(["doctor", str(clean)]) == 0
    assert "verdict: ok" in capsys.readouterr().out


def test_quaternion_message_names_the_columns(arm, tmp_path, capsys):
    rng = np.random.default_rng(4)
    _, rotations, wrenches = _data(arm, rng)
    xyzw = matrix_to_quaternion(rotations)[:, [1, 2, 3, 0]]
    path = write_csv(
        tmp_path / "q.csv", ["qw", "qx", "qy", "qz", *WRENCH], np.hstack([xyzw, wrenches]).tolist()
    )
    assert main(["calibrate", str(path)]) == 2
    err = capsys.readouterr().err
    assert "the quaternion as x,y,z,w" in err and "name the columns qx,qy,qz,qw" in err


def test_too_few_poses_is_undetermined_not_ok(tmp_path, capsys):
    path = tmp_path / "one.csv"
    path.write_text(
        "alpha,beta,gamma,fx,fy,fz,mx,my,mz\n0,0,0,1,2,3,0.1,0.2,0.3\n10,0,0,1,2,3,0.1,0.2,0.3\n"
    )
    assert main(["doctor", str(path)]) == 0
    assert (
        "verdict: undetermined: no reading could be fitted: fewer than 3 poses"
        in capsys.readouterr().out
    )


def test_pure_noise_is_never_explained_by_a_convention(arm):
    """Readings without any structure: no convention may be named (nothing explains noise)."""
    rng = np.random.default_rng(77)
    named = []
    for _ in range(100):
        count = int(rng.integers(3, 15))
        wrenches = rng.normal(size=(count, 6)) * 10 ** rng.uniform(-3, 3)
        angles = rng.uniform(-180, 180, (count, 3))
        report = diagnose_table(
            _table(["alpha", "beta", "gamma", *WRENCH], np.hstack([angles, wrenches]))
        )
        if report.verdict in ("mistake", "suspect"):
            named.append(report.message)
    assert named == []


def test_a_table_without_wrench_columns_is_refused_by_name(tmp_path):
    """A missing wrench column is an ftkin error naming it (it was a bare ValueError)."""
    path = tmp_path / "no_fx.csv"
    path.write_text("alpha,beta,gamma,fy,fz,mx,my,mz\n0,0,0,2,3,0.1,0.2,0.3\n")
    with pytest.raises(ftkin.InvalidSamples, match=r"missing wrench column\(s\) \['fx'\]"):
        ftkin.io.diagnose_samples(path)
