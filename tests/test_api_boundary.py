"""One boundary: the Python API refuses what the command line refuses, with the same words.

Each malformed input goes through both doors: the library call raises an ftkin error, and
``ftkin calibrate`` (``main([...])``) exits 2 printing the same message. The data are made by
hand from a known tool (raw = bias + the weight in the sensor frame, and its moment about the
sensor origin), the orientations converted by scipy (its own quaternion and Euler code), never by
the code under test.
"""

from __future__ import annotations

import logging

import numpy as np
import pinocchio as pin
import pytest
from scipy.spatial.transform import Rotation

import ftkin
from ftkin.cli import main

WRENCH = ["fx", "fy", "fz", "mx", "my", "mz"]
MASS = 0.322  # [kg] the tool of issue 37
G = 9.81  # [m/s²]
BIAS = np.array([1.5, -2.0, 3.0, 0.05, -0.03, 0.02])  # [N, N·m]
COM = np.array([0.01, -0.02, 0.06])  # [m] sensor frame
NOISE = np.array([0.02, 0.02, 0.02, 0.001, 0.001, 0.001])  # [N, N·m] per reading


def _raw(rotations: np.ndarray, rng) -> np.ndarray:
    """Raw readings at ``R_BS``: bias + the tool's weight in the sensor frame and its moment."""
    weight_in_sensor = np.einsum("nji,j->ni", rotations, [0.0, 0.0, -MASS * G])  # R^T (0,0,-mg)
    moment = np.cross(COM, weight_in_sensor)
    return (
        BIAS + np.hstack([weight_in_sensor, moment]) + rng.normal(0.0, NOISE, (len(rotations), 6))
    )


@pytest.fixture(scope="module")
def poses(arm):
    """20 joint configurations [rad] within the bundled arm's limits, their ``R_BS`` (Pinocchio
    itself) and raw readings."""
    rng = np.random.default_rng(37)
    q = rng.uniform(0.8 * arm.lower_limits, 0.8 * arm.upper_limits, size=(20, arm.nq))
    model = arm.model
    data = model.createData()
    frame = model.getFrameId("ft_sensor")
    rotations = []
    for configuration in q:
        pin.framesForwardKinematics(model, data, configuration)
        rotations.append(data.oMf[frame].rotation.copy())
    rotations = np.array(rotations)
    return q, rotations, _raw(rotations, rng)


def _csv(path, header, values) -> str:
    lines = [",".join(header)] + [",".join(repr(float(v)) for v in row) for row in values]
    path.write_text("\n".join(lines) + "\n")
    return str(path)


def _cli_error(capsys, *argv) -> str:
    capsys.readouterr()
    code = main(["calibrate", *argv])
    err = capsys.readouterr().err
    assert code == 2, err
    assert "Traceback" not in err
    return err


# ---------------------------------------------------------------- joint angles in degrees
def test_degrees_beyond_two_pi_refused_by_both_doors(arm, poses, tmp_path, capsys):
    q, _, wrenches = poses
    degrees = np.degrees(q)  # issue 37: 0.137 kg and a 25° tilt, with log warnings only
    with pytest.raises(ftkin.InvalidSamples, match="outside ±2π") as api:
        ftkin.Samples.from_joint_positions(arm, degrees, wrenches)
    tail = str(api.value).split("outside ±2π")[1]
    assert "must be in radians (these look like degrees" in tail
    path = _csv(
        tmp_path / "deg.csv",
        [f"q{i + 1}" for i in range(6)] + WRENCH,
        np.hstack([degrees, wrenches]),
    )
    err = _cli_error(capsys, path)
    assert "outside ±2π" + tail in err


@pytest.mark.parametrize(("excess", "refused"), [(0.45, False), (0.55, True)])
def test_a_joint_far_outside_its_limits_is_degrees_by_both_doors(
    arm, poses, tmp_path, capsys, caplog, excess, refused
):
    """Every |q| ≤ 2π: the limits decide. joint2's upper limit (1.134 rad in the URDF) plus
    0.55 rad is refused as degrees (every value read as degrees is within the limits), plus 0.45
    is a warned value in radians (a URDF narrower than its robot)."""
    q, rotations, wrenches = poses
    q = q.copy()
    upper = 1.13446401  # joint2's upper limit in the bundled URDF [rad] (65°)
    assert arm.upper_limits[1] == pytest.approx(upper, abs=1e-12)
    q[0, 1] = upper + excess
    header = [f"q{i + 1}" for i in range(6)] + WRENCH
    path = _csv(tmp_path / "q.csv", header, np.hstack([q, wrenches]))
    if refused:
        with pytest.raises(ftkin.InvalidSamples, match="more than 0.5 rad outside its limits"):
            ftkin.Samples.from_joint_positions(arm, q, wrenches)
        err = _cli_error(capsys, path)
        assert "more than 0.5 rad outside its limits [-2.793, 1.134] rad" in err
        assert "these look like degrees" in err
        return
    with caplog.at_level(logging.WARNING):
        samples = ftkin.Samples.from_joint_positions(arm, q, wrenches)
    assert any(
        "'joint2' has 1 value(s) outside the URDF limits" in r.getMessage() for r in caplog.records
    )
    assert samples.joint_positions[0, 1] == pytest.approx(upper + excess, abs=0)
    capsys.readouterr()
    assert main(["calibrate", path]) == 0, capsys.readouterr().err


def test_small_angles_in_degrees_within_the_limits_are_taken_as_radians(arm, poses):
    """Documented: all |q| a few degrees and within the limits read either way: radians."""
    _, _, wrenches = poses
    small_degrees = np.tile([2.0, -2.0, 1.5, -3.0, 2.0, 5.0], (len(wrenches), 1))  # [deg]
    assert np.all((small_degrees > arm.lower_limits) & (small_degrees < arm.upper_limits))
    samples = ftkin.Samples.from_joint_positions(arm, small_degrees, wrenches)
    assert samples.joint_positions[0, 5] == pytest.approx(5.0, abs=0)


def test_the_tick_holds_and_reports_degrees_where_compensate_refuses(arm, poses):
    q, rotations, wrenches = poses
    calibration = ftkin.SensorModel(BIAS[:3], BIAS[3:], np.array([0.0, 0.0, -MASS * G]), COM, G)
    compensator = ftkin.Compensator(calibration, arm)
    with pytest.raises(ftkin.InvalidInput, match="these look like degrees") as refused:
        compensator.compensate(np.degrees(q[0]), wrenches[0])
    controller = ftkin.JointAdmittance(arm, ftkin.Admittance(k2=1e-3), compensator)
    dq = controller.step(np.degrees(q[0]), wrenches[0], 1e-3)
    status = controller.last_status
    assert np.all(dq == 0.0) and status.held
    assert status.fault is ftkin.control.SensorFault.JOINT_RANGE
    assert status.event == f"{refused.value}: holding"
    controller.reset()
    # at the margin (0.05 rad past a limit: encoder overshoot) the tick runs; beyond, it holds
    for past, held in ((0.04, False), (0.06, True)):
        at_limit = q[0].copy()
        at_limit[1] = arm.upper_limits[1] + past
        controller.reset()
        controller.step(at_limit, wrenches[0], 1e-3)
        fault = controller.last_status.fault
        assert (fault is ftkin.control.SensorFault.JOINT_RANGE) is held, (past, fault)


# ---------------------------------------------------------------- orientations given directly
def _matrix_header():
    return [f"r{i}{j}" for i in (1, 2, 3) for j in (1, 2, 3)]


def _both_doors(samples, path, capsys, reading: str, fix: str) -> None:
    with pytest.raises(ftkin.ConventionMistake) as api:
        ftkin.calibrate(samples)
    assert api.value.reading == reading and api.value.fix == fix
    err = _cli_error(capsys, path)
    assert f"the data fit when read with {reading} (" in err and fix in err


def test_transposed_rotations_refused_by_both_doors(poses, tmp_path, capsys):
    _, rotations, wrenches = poses
    transposed = np.transpose(rotations, (0, 2, 1))  # R_SB given for R_BS
    path = _csv(
        tmp_path / "rsb.csv",
        _matrix_header() + WRENCH,
        np.hstack([transposed.reshape(-1, 9), wrenches]),
    )
    _both_doors(
        ftkin.Samples.from_rotations(transposed, wrenches),
        path,
        capsys,
        "the matrix transposed (R_SB, or the entries column-major)",
        "write R_BS row-major: r12 is row 1, column 2 (swap rIJ and rJI); in Python give R_BS, "
        "the sensor's orientation in the base frame (R_SB.transpose(0, 2, 1))",
    )
    result = ftkin.calibrate(ftkin.Samples.from_rotations(rotations, wrenches))  # as it should be
    assert result.tool_weight / G == pytest.approx(MASS, abs=0.01)


def test_xyzw_quaternions_refused_by_both_doors_and_through_load_samples(poses, tmp_path, capsys):
    _, rotations, wrenches = poses
    xyzw = Rotation.from_matrix(rotations).as_quat()  # scipy's own order: x, y, z, w
    header = ["qw", "qx", "qy", "qz", *WRENCH]  # the columns named w first, holding x first
    path = _csv(tmp_path / "xyzw.csv", header, np.hstack([xyzw, wrenches]))
    reading = "the quaternion as x,y,z,w"
    fix = (
        "name the columns qx,qy,qz,qw (the order they hold); in Python give [qw, qx, qy, qz] to "
        "Samples.from_quaternions (quaternions[:, [3, 0, 1, 2]])"
    )
    _both_doors(ftkin.Samples.from_quaternions(xyzw, wrenches), path, capsys, reading, fix)
    loaded = ftkin.load_samples(path)  # issue 37: advice to flip the sensor's sign
    with pytest.raises(ftkin.ConventionMistake, match="quaternion as x,y,z,w"):
        ftkin.calibrate(loaded.samples)
    fixed = ftkin.calibrate(ftkin.Samples.from_quaternions(xyzw[:, [3, 0, 1, 2]], wrenches))
    assert fixed.tool_weight / G == pytest.approx(MASS, abs=0.01)


def test_euler_angles_in_radians_refused_by_both_doors(poses, tmp_path, capsys):
    _, rotations, wrenches = poses
    radians = Rotation.from_matrix(rotations).as_euler("ZYX")  # intrinsic: Rz(α) Ry(β) Rx(γ)
    path = _csv(
        tmp_path / "rad.csv", ["alpha", "beta", "gamma", *WRENCH], np.hstack([radians, wrenches])
    )
    _both_doors(
        ftkin.Samples.from_euler_zyx_deg(radians, wrenches),
        path,
        capsys,
        "Euler angles in radians",
        "give alpha, beta, gamma in degrees (multiply by 180/π; Samples.from_euler_zyx_deg takes "
        "degrees)",
    )
    degrees = ftkin.calibrate(ftkin.Samples.from_euler_zyx_deg(np.degrees(radians), wrenches))
    assert degrees.tool_weight / G == pytest.approx(MASS, abs=0.01)
    path = _csv(
        tmp_path / "deg.csv",
        ["alpha", "beta", "gamma", *WRENCH],
        np.hstack([np.degrees(radians), wrenches]),
    )
    capsys.readouterr()
    assert main(["calibrate", path]) == 0, capsys.readouterr().err


def test_the_check_is_an_option_of_both_doors(poses, tmp_path, capsys):
    _, rotations, wrenches = poses
    transposed = np.transpose(rotations, (0, 2, 1))
    samples = ftkin.Samples.from_rotations(transposed, wrenches)
    with pytest.raises(ftkin.FtkinError) as fitted:  # fitted as given: only the fit's own checks
        ftkin.calibrate(samples, convention_check=False)
    assert not isinstance(fitted.value, ftkin.ConventionMistake)
    with pytest.raises(ftkin.InvalidInput, match="convention_check must be True or False"):
        ftkin.CalibrationOptions(convention_check="no")


# ---------------------------------------------------------------- plan_poses' floor
def test_plan_poses_keeps_the_floor_ftkin_plan_keeps(arm):
    from ftkin.cli import build_parser
    from ftkin.cli.pose_options import constraints_from_args

    args = build_parser(["plan"]).parse_args(["plan", "-n", "4"])
    assert ftkin.PlanSpec(4).constraints.floor_height == constraints_from_args(args).floor_height
    assert ftkin.PlanSpec(4).constraints.floor_height == pytest.approx(0.1, abs=0)
    plan = ftkin.plan_poses(arm, 4, seed=3, candidates=40)
    model = arm.model
    data = model.createData()
    frames = [model.getFrameId(name) for name in ("ft_sensor", "tool")]
    for configuration in plan.joint_positions:
        pin.framesForwardKinematics(model, data, configuration)
        heights = [data.oMf[frame].translation[2] for frame in frames]
        assert min(heights) >= 0.1, heights
