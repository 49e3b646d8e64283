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
    used = code + "\nimport numpy as np\nimu = ftkin.calibration.ImuSamples"
    used += "\nimu.from_arrays(np.eye(3) * 9.81, np.zeros((3, 6)))"
    assert "ftkin.calibration.imu_samples" in _modules_after(used)


_EVERY_SUBMODULE = r"""
import os, pkgutil, sys
import ftkin

def walk(path, prefix):
    for info in pkgutil.iter_modules(path):
        if info.name == "__main__":  # ``python -m ftkin.cli``'s entry, not an attribute
            continue
        yield prefix + info.name
        if info.ispkg:
            yield from walk([os.path.join(path[0], info.name)], prefix + info.name + ".")

names = sorted(walk(ftkin.__path__, "ftkin."))
failures, fresh = [], 0
for name in names:
    parent_name, _, last = name.rpartition(".")
    parent = sys.modules.get(parent_name)
    if name in sys.modules and parent is not None:
        # loaded by an earlier one's imports: forget the attribute the import system set, so
        # the access below goes through the package's __getattr__ as a first one would
        parent.__dict__.pop(last, None)
    else:
        fresh += 1
    try:
        value = ftkin
        for part in name.split(".")[1:]:
            value = getattr(value, part)
        if value is not sys.modules[name]:
            failures.append(name + ":not-the-module")
    except AttributeError as error:
        failures.append(f"{name}:AttributeError({error})".replace(" ", "_"))
    except ImportError:
        pass  # an optional extra that is not installed: not this test's concern
print(len(names), fresh, " ".join(failures))
"""


def test_every_submodule_resolves_by_attribute_after_import_ftkin():
    """``ftkin.kinematics.rotations`` (and every other submodule, enumerated by pkgutil from the
    files) resolves by attribute after ``import ftkin`` alone, whatever was imported before.

    A fresh interpreter reaches each submodule by an attribute chain from ``ftkin``; one that an
    earlier one's imports already loaded is first dropped from its package's namespace (it stays
    in ``sys.modules``), so every access goes through the package's ``__getattr__``.
    """
    environment = {**os.environ, "PYTHONPATH": str(ROOT)}
    out = subprocess.run(
        [sys.executable, "-c", _EVERY_SUBMODULE],
        capture_output=True,
        text=True,
        env=environment,
        check=True,
        cwd=ROOT,
    ).stdout.split()
    count, fresh, failures = int(out[0]), int(out[1]), out[2:]
    assert count > 150  # the walk found the package's modules (179 on 2026-12-03)
    assert fresh > 10  # some were reached before anything had loaded them
    assert failures == [], " ".join(failures)
