"""Each option is checked once, where it enters, and nothing is evaluated before it is needed:
``calibrate()`` on samples without times imports no drift model, the mount mode's text is
checked by one function and once per call, ``g`` and ``loss`` by one rule each."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import numpy as np

import ftkin
from ftkin.calibration.mount import MountMode

PACKAGE = Path(ftkin.__file__).resolve().parent


def _sources():
    return {path: path.read_text() for path in PACKAGE.rglob("*.py")}


def test_calibrate_without_times_imports_no_drift_model():
    script = """
import sys, numpy as np, ftkin
from ftkin.sim.sensor import paper_like_truth
arm = ftkin.Arm.default()
rng = np.random.default_rng(0)
sensor = ftkin.SimulatedSensor(paper_like_truth(), ftkin.SensorNoise.paper())
samples = sensor.samples_at_configurations(arm, arm.random_configurations(9, rng, margin=0.3), rng)
assert samples.times is None
ftkin.calibrate(samples)
print(sorted(m for m in sys.modules if m.startswith("ftkin.calibration")))
"""
    done = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, timeout=60
    )
    assert done.returncode == 0, done.stderr
    loaded = done.stdout
    for module in ("drift_poly", "drift_walk", "random_walk", "drift_fit", "cross_validation"):
        assert f"ftkin.calibration.{module}" not in loaded, module


def test_the_mount_mode_text_is_checked_once_per_calibration(monkeypatch, arm, truth):
    texts = []
    original = MountMode.of.__func__

    def counting(cls, value):
        if not isinstance(value, MountMode):
            texts.append(value)
        return original(cls, value)

    monkeypatch.setattr(MountMode, "of", classmethod(counting))
    rng = np.random.default_rng(1)
    q = arm.random_configurations(12, rng, margin=0.3)
    rotations = arm.rotation_sensor_to_base(q)
    samples = ftkin.Samples.from_joint_positions(arm, q, truth.predict(rotations))
    ftkin.calibrate(samples, estimate_mount="yaw")
    assert texts == ["yaw"]  # CalibrationOptions; the fit, the conventions and the result trust it


def test_one_rule_for_g_loss_and_the_mount_mode():
    sources = _sources()
    rules = {
        r"GRAVITY_RANGE\[|\*GRAVITY_RANGE": "calibration/model.py",  # check_gravity
        r"as_positive\(\s*g\b": None,  # no other rule for g
        r"not in LOSSES": "calibration/fit_options.py",
        r"not in MOUNT_MODES|return cls\(value\)": "calibration/mount.py",
    }
    for pattern, home in rules.items():
        found = sorted(
            str(path.relative_to(PACKAGE))
            for path, text in sources.items()
            if re.search(pattern, text)
        )
        assert found == ([] if home is None else [home]), (pattern, found)
