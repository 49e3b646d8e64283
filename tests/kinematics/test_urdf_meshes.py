"""URDFs as users have them: meshes named relative to the URDF's folder, ``package://`` packages
beside or above it, a relocated copy, a mesh that really is missing, a sensor frame no joint
moves. The regression: the bundled FR3 and franky-sim's own fr3.urdf could not plan ("Mesh
meshes/link0_coll.stl could not be found"), so a robot session failed before it moved."""

from __future__ import annotations

import shutil
import time
from pathlib import Path

import numpy as np
import pytest

from ftkin import Arm, plan_poses
from ftkin.calibration.information import SensorNoise
from ftkin.cli import main
from ftkin.exceptions import InvalidInput
from ftkin.kinematics.fr3 import fr3_urdf_path
from ftkin.kinematics.urdf_loading import mesh_candidates, resolve_mesh_paths
from ftkin.sim.sensor import paper_like_truth

FR3 = fr3_urdf_path()


def test_plan_the_bundled_fr3_with_collision_checks(capsys):
    argv = ["plan", "--urdf", str(FR3), "--sensor-frame", "fr3_hand", "--n", "12"]
    assert main(argv) == 0
    assert "no self-collision" in capsys.readouterr().out


def test_a_relocated_copy_plans_and_a_missing_mesh_is_named_once(tmp_path, capsys):
    copy = tmp_path / "elsewhere" / "fr3"
    shutil.copytree(FR3.parent, copy)
    argv = ["plan", "--urdf", str(copy / "fr3.urdf"), "--sensor-frame", "fr3_hand", "--n", "12"]
    assert main(argv) == 0
    capsys.readouterr()
    (copy / "meshes" / "link3_coll.stl").unlink()
    assert main(argv) == 2
    error = capsys.readouterr().err
    assert error.count("meshes/link3_coll.stl") == 1 and "--package-dir" in error
    assert "Traceback" not in error


def test_package_uris_resolve_beside_or_above_the_urdf(tmp_path):
    """``package://NAME/...`` with the package NAME an ancestor of the URDF (named NAME or by its
    package.xml), or a folder NAME beside the URDF."""
    text = FR3.read_text()
    package = tmp_path / "ws" / "src" / "my_fr3_description"
    (package / "urdf").mkdir(parents=True)
    shutil.copytree(FR3.parent / "meshes", package / "meshes")
    (package / "package.xml").write_text("<package><name>my_fr3</name></package>")
    urdf = package / "urdf" / "fr3.urdf"
    urdf.write_text(text.replace('filename="meshes/', 'filename="package://my_fr3/meshes/'))
    resolved, missing = resolve_mesh_paths(urdf.read_text(), urdf)
    assert not missing and str(package / "meshes" / "link0_coll.stl") in resolved
    arm = Arm.from_urdf(urdf, "fr3_hand")
    assert arm.geometry("collision").ngeoms > 0
    # a folder named as the package beside the URDF
    beside = tmp_path / "beside"
    shutil.copytree(FR3.parent, beside / "fr3_pkg")
    (beside / "robot.urdf").write_text(
        text.replace('filename="meshes/', 'filename="package://fr3_pkg/meshes/')
    )
    assert mesh_candidates("package://fr3_pkg/meshes/x.stl", beside / "robot.urdf", [])[0] != []
    assert Arm.from_urdf(beside / "robot.urdf", "fr3_hand").geometry("collision").ngeoms > 0


def test_a_sensor_frame_fixed_to_the_base_is_refused_as_such(capsys):
    with pytest.raises(InvalidInput, match="fixed to the base link: no joint moves it.*fr3_link8"):
        Arm.from_urdf(FR3, "fr3_link0")
    assert main(["plan", "--urdf", str(FR3), "--sensor-frame", "fr3_link0", "--n", "6"]) == 2
    error = capsys.readouterr().err
    assert "fixed to the base link" in error and "joint" in error and "feasible" not in error


class _PoseSensor:
    """Readings of a simulated tool at the fake robot's pose (FK of the arm), with noise."""

    def __init__(self, robot, arm, seed=0):
        self.robot, self.arm, self.truth = robot, arm, paper_like_truth()
        self.rng, self.count = np.random.default_rng(seed), 0
        self.noise = np.repeat(SensorNoise.paper().channel_std[[0, 3]], 3)

    def read(self):
        self.count += 1
        rotation = self.arm.rotation_sensor_to_base(self.robot.q)
        wrench = self.truth.predict(rotation[None])[0] + self.noise * self.rng.standard_normal(6)
        return self.count * 1e-3, wrench


def test_calibrate_on_robot_with_franky_sims_own_urdf_without_package_dirs(tmp_path):
    franky_sim = pytest.importorskip("franky_sim", reason="franky-sim is not installed")
    from ftkin.robot import Stillness, calibrate_on_robot
    from tests.robot.fakes import FakeRobot

    urdf = Path(franky_sim.__file__).parent / "assets" / "fr3.urdf"
    arm = Arm.from_urdf(urdf, "fr3_hand")  # fingers locked, no package_dirs
    assert arm.nq == 7 and arm.package_dirs == []
    robot = FakeRobot(nq=7)
    robot.q = 0.5 * (arm.lower_limits + arm.upper_limits)
    started = time.monotonic()
    result = calibrate_on_robot(
        robot,
        _PoseSensor(robot, arm),
        arm,
        n_poses=6,
        readings_per_pose=20,
        samples_path=tmp_path / "samples.csv",
        verify_poses=0,
        stillness=Stillness(window=5, stale_after=5.0),
    )
    assert len(robot.moves) == 6 and time.monotonic() - started < 60
    np.testing.assert_allclose(result.tool_weight, paper_like_truth().tool_weight, rtol=0.02)
    assert plan_poses(arm, 4, seed=1).joint_positions.shape == (4, 7)  # with the collision check
