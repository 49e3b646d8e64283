"""Importing ftkin loads no heavy optional dependency; ``ftkin --version`` loads not even numpy."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import ftkin

ROOT = Path(__file__).resolve().parent.parent
HEAVY = ("scipy", "matplotlib", "meshcat", "rosbags", "yourdfpy", "mujoco")


def _modules_after(code: str) -> set[str]:
    environment = {**os.environ, "PYTHONPATH": str(ROOT)}
    out = subprocess.run(
        [sys.executable, "-c", code + "\nimport sys; print(' '.join(sys.modules))"],
        capture_output=True,
        text=True,
        env=environment,
        check=True,
        cwd=ROOT,
    ).stdout
    return set(out.split())


def test_import_and_every_public_name_skip_the_heavy_dependencies():
    loaded = _modules_after("import ftkin\nfrom ftkin import *")
    assert "pinocchio" in loaded and not [name for name in HEAVY if name in loaded]


def test_version_answers_without_the_library():
    code = "from ftkin.cli import main\nassert main(['--version']) == 0"
    loaded = _modules_after(code)
    assert "numpy" not in loaded and "pinocchio" not in loaded and "ftkin.control" not in loaded


def test_lazy_names_are_the_modules_objects():
    from ftkin.control.compensation import Compensator

    assert ftkin.Compensator is Compensator
    assert "Compensator" in dir(ftkin)


def test_the_imus_modules_load_with_their_first_use():
    """The IMU's and the fused fit's modules stay out of the FK paths (the control loop, the
    robot session, the calibration file), and load once a calibration from the IMU is asked for.
    """
    imu = {"ftkin.calibration.imu_fit", "ftkin.calibration.fused_fit", "ftkin.io.imu_columns"}
    imu |= {"ftkin.control.imu_compensation", "ftkin.calibration.imu_samples"}
    code = (
        "import ftkin\nfrom ftkin import *\nimport ftkin.robot.session, ftkin.robot.loop\n"
        "import ftkin.control.joint_admittance, ftkin.io.calibration_file"
    )
    assert not imu & _modules_after(code)
    used = code + "\nimport numpy as np\nftkin.Samples.from_imu(np.eye(3) * 9.81, np.zeros((3, 6)))"
    assert "ftkin.calibration.imu_samples" in _modules_after(used)
