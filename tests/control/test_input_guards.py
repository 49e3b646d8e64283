"""Bad input on the control paths is an ftkin error, never a TypeError or a silently ignored
argument.
"""

from __future__ import annotations

import numpy as np
import pytest

from ftkin import Admittance, Compensator, InvalidInput, JointAdmittance
from ftkin.sim.sensor import paper_like_truth


def test_compensate_refuses_a_scalar_or_short_reading(arm):
    compensator = Compensator(paper_like_truth(), arm)
    for raw in (5.0, [1.0, 2.0, 3.0], "abc"):
        with pytest.raises(InvalidInput):
            compensator.compensate(np.zeros(arm.nq), raw)


def test_admittance_update_checks_its_inputs():
    law = Admittance(k2=1e-3)
    np.testing.assert_allclose(
        law.update([0, 0, 2.0, 0, 0, 0], 0.01), [0, 0, 2e-3, 0, 0, 0]
    )  # a list is fine
    for dt in (0.0, -0.01, float("nan"), "x"):
        with pytest.raises(InvalidInput, match="dt must be"):
            law.update(np.zeros(6), dt)
    with pytest.raises(InvalidInput):
        law.update([1.0, 2.0], 0.01)


def test_joint_velocities_need_a_dynamic_compensator(arm):
    controller = JointAdmittance(arm, Admittance(k2=1e-3), Compensator(paper_like_truth(), arm))
    q = arm.random_configurations(1, np.random.default_rng(0), margin=0.5)[0]
    raw = paper_like_truth().predict(arm.rotation_sensor_to_base(q[None]))[0]
    with pytest.raises(InvalidInput, match="DynamicCompensator only"):
        controller.step(
            q, raw, 1e-3, joint_velocities=np.zeros(arm.nq), joint_accelerations=np.zeros(arm.nq)
        )
    with pytest.raises(InvalidInput, match="go together"):
        controller.step(q, raw, 1e-3, joint_velocities=np.zeros(arm.nq))
    assert controller.step(q, raw, 1e-3).shape == (arm.nq,)


def test_compensate_refuses_degrees_for_radians(arm):
    """Joint angles in degrees used to give a wrong wrench without a word."""
    compensator = Compensator(paper_like_truth(), arm)
    q = np.array([0.0, 0.0, -0.5236, 0.0, -1.0472, 0.0])  # [rad], within the limits
    raw = paper_like_truth().predict(arm.rotation_sensor_to_base(q[None]))[0]
    np.testing.assert_allclose(compensator.compensate(q, raw), np.zeros(6), atol=1e-12)
    with pytest.raises(InvalidInput, match=r"joint3 = -30[.0-9]* is outside its limits.*degrees"):
        compensator.compensate(np.degrees(q), raw)
    with pytest.raises(InvalidInput, match="degrees"):
        compensator.compensate_batch(np.degrees(q)[None], raw[None])
    with pytest.raises(InvalidInput, match="degrees"):
        compensator.rezero(np.degrees(q), raw)
    # a joint a hair past its limit (encoder overshoot at a hard stop) is still a measurement
    edge = q.copy()
    edge[2] = arm.lower_limits[2] - 0.01
    assert np.all(np.isfinite(compensator.compensate(edge, raw)))


def test_a_complex_q_is_a_held_fault_not_a_cast(arm):
    import warnings

    controller = JointAdmittance(arm, Admittance(k2=1e-3), Compensator(paper_like_truth(), arm))
    q = arm.random_configurations(1, np.random.default_rng(0), margin=0.5)[0]
    raw = paper_like_truth().predict(arm.rotation_sensor_to_base(q[None]))[0]
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # numpy's ComplexWarning would be an error here
        dq = controller.step(q + 1e-3j, raw, 1e-3)
    np.testing.assert_array_equal(dq, np.zeros(arm.nq))
    assert controller.last_status.fault == "not_finite"


@pytest.mark.parametrize(
    "raw",
    [
        np.array([True] * 6),
        np.array(["1"] * 6),
        np.zeros(6) + 0j,
        np.ma.masked_array(np.zeros(6), mask=[1, 0, 0, 0, 0, 0]),
    ],
    ids=["booleans", "text", "complex", "masked"],
)
def test_compensate_refuses_what_is_not_a_real_reading(arm, raw):
    """Booleans, text, complex and masked entries were cast (True as 1 N, the mask dropped)."""
    with pytest.raises(InvalidInput, match="raw_wrench"):
        Compensator(paper_like_truth(), arm).compensate(np.zeros(arm.nq), raw)


def test_the_arm_a_calibration_file_and_drift_times_are_checked(arm, tmp_path):
    from ftkin import CalibrationFileError, load_calibration

    with pytest.raises(InvalidInput, match=r"ftkin.load_robot\('ur5e'\)"):
        Compensator(paper_like_truth(), "ur5e")
    for path in (None, 3, b"calib.json"):
        with pytest.raises(CalibrationFileError, match="expected a calibration file's path"):
            load_calibration(path)
    with pytest.raises(InvalidInput, match="times .* must be finite, found nan at index 1"):
        Compensator(paper_like_truth(), arm).bias_at([0.0, np.nan, 1.0])
