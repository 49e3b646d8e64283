"""A calibration made by ``calibrate_on_robot`` on the user's own FR3 URDF (franky-sim's
``assets/fr3.urdf``, not the bundled file) is handed to the robot (issue 37 item 4).

``set_payload(result)`` takes the arm the calibration records, and the bundled FR3 (another file,
the same kinematics) is accepted as that arm; the load sent is checked against MuJoCo's own
bodies, independently of ftkin's URDF and payload code.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("franky", reason="franky-control is not installed (extra 'franka')")
franky_sim = pytest.importorskip(
    "franky_sim", reason="franky-sim is not installed (extra 'franka-sim')"
)

from ftkin import Arm, InvalidInput, load_robot  # noqa: E402
from ftkin.kinematics.fr3 import fr3_arm  # noqa: E402
from ftkin.robot import FrankaSim, calibrate_on_robot  # noqa: E402

from .test_franka_sim import (  # noqa: E402
    LOADED,
    PLAN,
    STILL,
    connect,
    load_from_simulated_bodies,
)


def test_set_payload_of_a_calibration_on_the_users_fr3_urdf(tmp_path):
    urdf = Path(franky_sim.__file__).parent / "assets" / "fr3.urdf"
    assert urdf.read_bytes() != fr3_arm().urdf_path.read_bytes()  # another file than ftkin's
    arm = Arm.from_urdf(urdf, "fr3_hand", "fr3_hand_tcp")  # the fingers locked by default
    assert arm.nq == 7
    with FrankaSim() as sim:
        robot = connect(sim.hostname, realtime=False, speed=0.8, **LOADED)
        result = calibrate_on_robot(
            robot,
            sim.sensor,
            arm,
            n_poses=3,
            readings_per_pose=30,
            samples_path=tmp_path / "samples.csv",
            output=tmp_path / "calib.json",
            verify_poses=0,
            stillness=STILL,
            g=sim.truth.g,
            plan_options=PLAN,
        )
        assert result.kinematics.urdf == str(urdf.resolve())
        end_effector = robot.end_effector()
        body = {"sensor_mass": sim.truth.sensor_mass, "sensor_com": sim.truth.sensor_com_flange}
        expected_mass, expected_com = load_from_simulated_bodies(sim.truth, end_effector)
        # the default arm is the calibration's own; the bundled FR3 has the same kinematics
        for given in ({}, {"arm": fr3_arm()}):
            robot.set_payload(result, **body, **given)
            mass, com, _ = robot.payload()  # in fr3_link8, as libfranka reports it
            np.testing.assert_allclose(mass, expected_mass, rtol=0.01)
            assert np.linalg.norm(com - expected_com) < 1e-3, (given, com, expected_com)
        # another arm is still refused, naming how it differs
        with pytest.raises(InvalidInput, match="sensor frame 'ft_sensor' is turned 45°"):
            robot.set_payload(result, arm=load_robot("panda"), **body)
