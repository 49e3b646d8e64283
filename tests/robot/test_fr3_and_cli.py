"""The bundled FR3, sensor factories and the robot CLI's error paths (no robot needed)."""

from __future__ import annotations

import logging

import numpy as np
import pinocchio as pin
import pytest

from ftkin.cli import main
from ftkin.exceptions import InvalidInput
from ftkin.kinematics.arm import Arm
from ftkin.kinematics.fr3 import fr3_arm, fr3_urdf_path
from ftkin.robot.sensor_factory import load_sensor_factory

NOWHERE = "127.254.254.254"  # loopback, and no franky-sim picks it (they start at 127.0.0.1)


def test_fr3_keeps_the_seven_arm_joints_and_says_so(caplog):
    with caplog.at_level(logging.INFO, logger="ftkin.kinematics.arm"):
        arm = fr3_arm()
    assert arm.nq == 7 and arm.joint_names == [f"fr3_joint{i}" for i in range(1, 8)]
    assert "locked fr3_finger_joint1" in caplog.text
    every = Arm.from_urdf(fr3_urdf_path(), "fr3_hand", locked_joints={})
    assert every.nq == 9


def test_fr3_sensor_frame_is_the_hand_frame(rng):
    arm = fr3_arm()
    full = pin.buildModelFromUrdf(str(fr3_urdf_path()))  # independent: the raw URDF, fingers at 0
    data = full.createData()
    hand = full.getFrameId("fr3_hand")
    flange = full.getFrameId("fr3_link8")
    for q in arm.random_configurations(5, rng):
        pin.framesForwardKinematics(full, data, np.r_[q, 0.0, 0.0])
        rotation, position = arm.frame_placement(q)
        np.testing.assert_allclose(rotation, data.oMf[hand].rotation, atol=1e-12)
        np.testing.assert_allclose(position, data.oMf[hand].translation, atol=1e-12)
        # the hand frame is the flange turned by -45 degrees about z
        turn = data.oMf[flange].rotation.T @ data.oMf[hand].rotation
        np.testing.assert_allclose(turn, pin.rpy.rpyToMatrix(0, 0, -np.pi / 4), atol=1e-12)


def test_fr3_collision_geometry_loads():
    assert fr3_arm().geometry("collision").ngeoms > 7


def test_sensor_factory_imports_and_checks():
    sensor = load_sensor_factory("tests.robot.fakes:FakeSensor", noise=0.0)
    assert sensor.read()[1].shape == (6,)
    with pytest.raises(InvalidInput, match="MODULE:FACTORY"):
        load_sensor_factory("no colon")
    with pytest.raises(InvalidInput, match="cannot import"):
        load_sensor_factory("no_such_module_here:thing")
    with pytest.raises(InvalidInput, match="has no read"):
        load_sensor_factory("tests.robot.fakes:FakeRobot")


def test_cli_errors_are_one_line(tmp_path, capsys):
    out = str(tmp_path / "calib.json")
    code = main(
        [
            "robot",
            "calibrate",
            "--franka",
            NOWHERE,
            "--no-realtime",
            "--sensor",
            "no_such_module_here:x",
            "-o",
            out,
        ]
    )
    assert code == 2
    assert "cannot import the sensor module" in capsys.readouterr().err
    code = main(
        [
            "robot",
            "calibrate",
            "--franka",
            NOWHERE,
            "--no-realtime",
            "--sensor",
            "tests.robot.fakes:FakeSensor",
            "-o",
            out,
        ]
    )
    err = capsys.readouterr().err
    assert code == 2 and "cannot connect to the robot" in err and "Traceback" not in err


def test_export_end_effector_only_for_franka_load(tmp_path, capsys):
    from dataclasses import replace

    from ftkin.calibration.model import SensorModel
    from ftkin.calibration.result import CalibrationResult
    from ftkin.io.calibration_file import save_calibration
    from ftkin.kinematics.record import KinematicsRecord

    model = SensorModel.from_tool(1.96, [0.0, 0.0, 0.07], [0, 0, 0], [0, 0, 0])
    result = CalibrationResult(
        model.force_offset, model.torque_offset, model.gravity_in_base, model.center_of_mass
    )
    path = tmp_path / "calib.json"
    save_calibration(replace(result, kinematics=KinematicsRecord.from_arm(fr3_arm())), path)
    load = tmp_path / "load.yaml"
    args = ["export", str(path), "-o", str(load), "--end-effector", "0.73", "0", "0", "0.03"]
    assert main([*args, "--format", "franka-load"]) == 0
    assert "mass 1.23" in capsys.readouterr().out
    assert main([*args, "--format", "ur-payload", "-o", str(tmp_path / "ur.yaml")]) == 2
    assert "--format franka-load" in capsys.readouterr().err
    assert (
        main(
            [
                *args[:-5],
                "--end-effector",
                "3",
                "0",
                "0",
                "0",
                "--format",
                "franka-load",
                "-o",
                str(tmp_path / "x.yaml"),
            ]
        )
        == 2
    )
    assert "negative mass" in capsys.readouterr().err


def test_the_contract_as_written():
    import dataclasses
    import inspect

    import ftkin.robot
    from ftkin.robot import FrankaRobot, LoopStats, calibrate_on_robot, run_admittance

    assert ftkin.robot.__all__ == sorted(ftkin.robot.__all__)
    for name in ftkin.robot.__all__:
        assert getattr(ftkin.robot, name) is not None, name
    realtime = inspect.signature(FrankaRobot).parameters["realtime"]
    assert realtime.kind is inspect.Parameter.KEYWORD_ONLY and realtime.default is True
    session = inspect.signature(calibrate_on_robot).parameters
    assert list(session)[:3] == ["robot", "sensor", "arm"]
    assert session["n_poses"].default == 12 and session["readings_per_pose"].default == 50
    assert {"poses", "samples_path", "resume"} <= set(session)
    assert "rate_hz" in {field.name for field in dataclasses.fields(LoopStats)}
    assert {"duration", "rate_hz"} <= set(inspect.signature(run_admittance).parameters)


def test_franka_robot_checks_its_arguments_and_names_a_missing_robot():
    from ftkin.exceptions import RobotConnectionLost
    from ftkin.robot import FrankaRobot

    with pytest.raises(InvalidInput, match="host"):
        FrankaRobot("")
    with pytest.raises(InvalidInput, match="speed must be in"):
        FrankaRobot(NOWHERE, speed=1.5)
    pytest.importorskip("franky", reason="franky-control is not installed (extra 'franka')")
    with pytest.raises(RobotConnectionLost, match=f"cannot connect to the robot at {NOWHERE}"):
        FrankaRobot(NOWHERE, realtime=False)


def test_a_fault_during_verification_stops_the_arm_and_keeps_the_calibration(caplog):
    from ftkin.calibration.model import SensorModel
    from ftkin.calibration.result import CalibrationResult
    from ftkin.exceptions import RobotError
    from ftkin.robot.session import verify_session
    from tests.robot.fakes import FakeRobot, FakeSensor

    class FailingRobot(FakeRobot):
        def move_to(self, q, while_moving=None):
            raise RobotError("reflex: joint 4 torque limit")

    model = SensorModel.from_tool(1.96, [0.0, 0.0, 0.07], [0, 0, 0], [0, 0, 0])
    result = CalibrationResult(
        model.force_offset, model.torque_offset, model.gravity_in_base, model.center_of_mass
    )
    robot = FailingRobot()
    with caplog.at_level(logging.WARNING, logger="ftkin.robot.session"):
        verification = verify_session(robot, FakeSensor(noise=0.0), fr3_arm(), result, 2)
    assert verification is None
    assert len(robot.stops) == 1  # the arm is stopped once
    assert "verification stopped (the arm is stopped): reflex: joint 4 torque limit" in caplog.text


class _LostConnectionFranky:
    """Stands in for franky: a motion whose start fails with libfranka's lost-connection text."""

    class NetworkException(Exception):
        pass

    JointMotion = JointState = staticmethod(lambda *args, **kwargs: None)


class _DeadRobot:
    def __init__(self, message):
        self.message, self.asked_for_errors, self.recovered = message, 0, 0

    def move(self, motion, asynchronous=True):
        raise RuntimeError(self.message)

    @property
    def has_errors(self):  # libfranka blocks here for its 1 s network timeout when the link is gone
        self.asked_for_errors += 1
        return True

    def recover_from_errors(self):
        self.recovered += 1


def _offline_franka(robot):
    from ftkin.robot.franka import FrankaRobot

    franka = FrankaRobot.__new__(FrankaRobot)  # no connection: the motion path alone
    franka.host, franka.nq, franka._franky, franka._robot = "sim", 7, _LostConnectionFranky, robot
    franka.move_timeout, franka.poll_period = 5.0, 0.005
    return franka


def test_a_lost_connection_is_raised_at_once_and_not_recovered():
    from ftkin.exceptions import RobotConnectionLost, RobotError

    dead = _DeadRobot("libfranka: TCP connection got interrupted.")
    with pytest.raises(RobotConnectionLost, match="connection is lost"):
        _offline_franka(dead).move_to(np.zeros(7))
    assert dead.asked_for_errors == 0  # asking would block for libfranka's network timeout
    refused = _DeadRobot("libfranka: Move command rejected: joint limits")
    with pytest.raises(RobotError, match="the robot refused") as error:
        _offline_franka(refused).move_to(np.zeros(7))
    assert not isinstance(error.value, RobotConnectionLost)
    assert refused.asked_for_errors == 1 and refused.recovered == 1  # a refusal is recovered
