"""The report's per-pose data show the real sensor: mount, sign and flip applied."""

from __future__ import annotations

import numpy as np

from ftkin import CalibrationResult, Samples
from ftkin.calibration.conventions import reading_signs
from ftkin.calibration.mount import exp_so3
from ftkin.viz.report import report_data


def test_report_residuals_vanish_for_the_true_mounted_sensor(arm, tool):
    mount = exp_so3([0.02, 0.01, 0.7])
    q = arm.random_configurations(6, np.random.default_rng(61), margin=0.3)
    raw = tool.predict(arm.rotation_sensor_to_base(q) @ mount.T) * reading_signs(-1, "z")
    samples = Samples.from_joint_positions(arm, q, raw)
    calibration = CalibrationResult(
        tool.force_offset,
        tool.torque_offset,
        tool.gravity_in_base,
        tool.center_of_mass,
        mount_rotation=mount,
        sensor_sign=-1,
        flip_axis="z",
    )
    data = report_data(calibration, samples)
    np.testing.assert_allclose(data["residuals"], 0.0, atol=1e-12)
    np.testing.assert_allclose(data["measured"], raw * reading_signs(-1, "z"), atol=1e-12)
    # the same samples against a calibration that ignores the mount do not fit
    assert np.abs(report_data(tool, samples)["residuals"]).max() > 1.0
