"""The float fast paths of the control tick and the compensation give the reference paths' numbers.

The reference tick below is the straightforward numpy form of METHOD.md §4–5
(arrays, ``np.cross``, ``np.clip``, LAPACK Cholesky factor then solve, a
per-joint limit loop); the library runs the same arithmetic on Python floats
with a lazily built status. ``dq`` must agree to 1e-12 over thousands of ticks
that visit every feature: faults, deadband, filter, saturation, damping near a
singularity, joint-limit scaling and the safety stop.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.linalg import lapack

from ftkin import Admittance, Arm, Compensator, InvalidInput, JointAdmittance
from ftkin.control import SensorFault
from ftkin.control.sensor_faults import FaultMonitor
from ftkin.sim.sensor import paper_like_truth
from ftkin.validation import as_rotation_batch, rotation_rows


class ReferenceTick:
    """``JointAdmittance.step`` written plainly in numpy (the reference path)."""

    def __init__(self, controller: JointAdmittance):
        self.c = controller
        self.law = controller.admittance
        self.monitor = FaultMonitor(controller.monitor.limits)
        self.previous = self.derivative = None
        self.holding = self.latched = False

    def step(self, q, raw, dt):
        c, law = self.c, self.law
        fault, _ = self.monitor.check(q, raw.tolist(), dt)
        if fault is not SensorFault.NONE:
            self.holding = True
            return np.zeros(len(q))
        rotation = c.arm.rotation_sensor_to_base(q) if np.isfinite(q).all() else None
        jacobian = c.arm.jacobian(q)
        calibration = c.compensator.calibration
        gravity = rotation.T @ calibration.gravity_in_base
        contact = (
            raw
            - calibration.bias
            - np.concatenate([gravity, np.cross(calibration.center_of_mass, gravity)])
        )
        if (
            self.latched
            or np.linalg.norm(contact[:3]) > c.force_limit
            or np.linalg.norm(contact[3:]) > c.torque_limit
        ):
            self.latched = True
            return np.zeros(len(q))
        r, frame = c.frame.point_in_sensor, c.frame.frame
        force, moment = contact[:3], contact[3:] - np.cross(r, contact[:3])
        axes = {"sensor": np.eye(3), "tool": c.frame.rotation_tool_to_sensor.T, "base": rotation}[
            frame
        ]
        wrench = np.concatenate([axes @ force, axes @ moment])
        error = law.desired_wrench + wrench
        error = error - np.clip(error, -law.deadband, law.deadband)
        if self.previous is None or self.holding:
            self.previous = error.copy()
            self.derivative = (
                np.zeros(6) if self.holding or self.derivative is None else self.derivative
            )
        self.holding = False
        alpha = -math.expm1(
            -dt * 2.0 * math.pi * law.derivative_cutoff
        )  # exact discretisation: 1 − e^(−dt/τ)
        self.derivative = self.derivative + alpha * ((error - self.previous) / dt - self.derivative)
        self.previous = error
        twist = law.selection * (law.k1 * self.derivative + law.k2 * error)
        for part, limit in (
            (slice(0, 3), law.max_linear_velocity),
            (slice(3, 6), law.max_angular_velocity),
        ):
            norm = np.linalg.norm(twist[part])
            if norm > limit:
                twist[part] *= limit / norm
        to_base = (
            rotation
            if frame == "sensor"
            else rotation @ c.frame.rotation_tool_to_sensor
            if frame == "tool"
            else np.eye(3)
        )
        linear, angular = to_base @ twist[:3], to_base @ twist[3:]
        sensor_twist = np.concatenate([linear - np.cross(angular, rotation @ r), angular])
        gram = jacobian @ jacobian.T
        factor, info = lapack.dpotrf(gram)
        w = np.prod(np.diag(factor)) if info == 0 else 0.0
        if w >= c.manipulability_threshold:
            dq = jacobian.T @ lapack.dpotrs(factor, sensor_twist)[0]
        else:
            damping = c.max_damping * (1.0 - w / c.manipulability_threshold)
            dq = jacobian.T @ lapack.dposv(gram + damping**2 * np.eye(6), sensor_twist)[1]
        scale = 1.0
        for position, velocity, lower, upper, speed in zip(
            q, dq, c.arm.lower_limits, c.arm.upper_limits, c.arm.velocity_limits
        ):
            bound = (
                min(speed, c.limit_gain * (upper - position))
                if velocity > 0
                else max(-speed, c.limit_gain * (lower - position))
            )
            if velocity != 0:
                scale = min(scale, max(0.0, bound / velocity))
        return dq * scale


@pytest.mark.parametrize(("frame", "ticks"), [("tool", 1500), ("sensor", 750), ("base", 750)])
def test_step_matches_the_reference_tick_over_thousands_of_ticks(arm, frame, ticks):
    truth = paper_like_truth()
    law = Admittance(
        k1=1e-3,
        k2=[2e-3] * 3 + [2e-2] * 3,
        frame=frame,
        force_deadband=0.05,
        torque_deadband=0.01,
        max_linear_velocity=0.02,
        max_angular_velocity=0.1,
    )
    # The reference does not model the oscillation detector (tested in test_oscillation.py): 0.5 N
    # white noise
    # per tick would trip it here.
    controller = JointAdmittance(
        arm, law, Compensator(truth, arm), limit_gain=2.0, oscillation=None
    )
    reference = ReferenceTick(controller)
    rng = np.random.default_rng(7)
    q = np.array([0.1, 0.2, -0.6, 0.3, -1.0, 0.2])
    seen = {"damped": 0, "scaled": 0, "saturated": 0, "held": 0, "stopped": 0}
    for k in range(ticks):
        raw = truth.predict(arm.rotation_sensor_to_base(q)) + rng.normal(size=6) * [
            0.5,
            0.5,
            0.5,
            0.05,
            0.05,
            0.05,
        ]
        raw += [3 * np.sin(k / 100), 0.0, 5 * np.cos(k / 70), 0.2, 0.0, 0.0]
        if k % 300 == 150:
            raw[1] = np.nan
        if k % 233 == 0:
            q = arm.random_configurations(1, rng)[0]
        if k % 233 == 100:
            q = np.clip(q, arm.lower_limits + 0.02, arm.upper_limits - 0.02)
            q[k % 6] = arm.upper_limits[k % 6] - 0.01  # near a position limit: limit scaling
        if k == ticks - 300:
            q = np.zeros(6)  # wrist singularity: damping
        if k == ticks - 100:
            raw[2] += 200.0  # safety stop, latched to the end
        dt = 1e-3 * (1 + 0.1 * rng.random())
        dq = controller.step(q, raw, dt)
        np.testing.assert_allclose(
            dq, reference.step(q, raw, dt), rtol=0, atol=1e-12, err_msg=f"tick {k}"
        )
        status = controller.last_status
        seen["damped"] += status.damping > 0
        seen["scaled"] += 0 < status.limit_scale < 1
        seen["saturated"] += np.linalg.norm(status.twist[:3]) >= 0.02 * (1 - 1e-12)
        seen["held"] += status.fault is not SensorFault.NONE
        seen["stopped"] += status.safety_stop
        q = q + dq * dt * 50
    assert all(count > 0 for count in seen.values()), seen


def test_status_is_built_on_request_with_the_ticks_numbers(arm):
    truth = paper_like_truth()
    controller = JointAdmittance(arm, Admittance(k2=1e-3, frame="tool"), Compensator(truth, arm))
    q = np.array([0.1, 0.2, -0.6, 0.3, -1.0, 0.2])
    raw = truth.predict(arm.rotation_sensor_to_base(q)) + [0.0, 0.0, 2.0, 0.0, 0.0, 0.0]
    assert controller.last_status is None
    dq = controller.step(q, raw, 1e-3)
    status = controller.last_status
    assert status is controller.last_status  # built once, then cached
    assert status.dq is dq and not status.held and status.event == ""
    np.testing.assert_allclose(status.contact_wrench, [0.0, 0.0, 2.0, 0.0, 0.0, 0.0], atol=1e-9)
    controller.reset()
    assert controller.last_status is None


def test_last_wrench_and_twist_are_the_status_values_without_building_it(arm):
    truth = paper_like_truth()
    controller = JointAdmittance(arm, Admittance(k2=1e-3, frame="tool"), Compensator(truth, arm))
    q = np.array([0.1, 0.2, -0.6, 0.3, -1.0, 0.2])
    raw = truth.predict(arm.rotation_sensor_to_base(q)) + [0.0, 0.0, 2.0, 0.0, 0.0, 0.0]
    assert controller.last_wrench_and_twist is None
    for reading in (raw, raw, np.full(6, np.nan)):  # moving ticks, then a held (fault) tick
        controller.step(q, reading, 1e-3)
        wrench, twist = controller.last_wrench_and_twist
        status = controller.last_status  # built after: the parts were read without it
        np.testing.assert_allclose(wrench, status.contact_wrench, rtol=1e-15, equal_nan=True)
        np.testing.assert_allclose(twist, status.twist, rtol=1e-15)
    assert status.held and np.all(np.isnan(wrench))
    np.testing.assert_allclose(controller.last_wrench_and_twist[0][2], np.nan, equal_nan=True)


def test_compensation_paths_agree(arm, rng):
    truth = paper_like_truth()
    compensator = Compensator(truth, arm)
    q = arm.random_configurations(200, rng)
    rotations = np.array([arm.frame_placement(x)[0] for x in q])  # Pinocchio, one call per row
    raw = truth.predict(rotations) + rng.normal(size=(200, 6))
    gravity = np.einsum("nji,j->ni", rotations, truth.gravity_in_base)
    expected = (
        raw
        - truth.bias
        - np.concatenate([gravity, np.cross(truth.center_of_mass, gravity)], axis=1)
    )
    for i in range(0, 200, 20):
        np.testing.assert_allclose(
            compensator.compensate(q[i], raw[i]), expected[i], rtol=0, atol=1e-12
        )
        np.testing.assert_allclose(
            compensator.compensate_rotation(rotations[i], raw[i]),
            compensator.compensate_unchecked(rotations[i], raw[i]),
            rtol=1e-12,
            atol=1e-12,
        )
    np.testing.assert_allclose(
        compensator.compensate_batch(rotations, raw), expected, rtol=0, atol=1e-12
    )
    np.testing.assert_allclose(compensator.compensate_batch(q, raw), expected, rtol=0, atol=1e-12)


def test_closed_form_rotation_checks_accept_and_refuse_like_the_gram_matrix(rng):
    good = np.array([Arm.default().rotation_sensor_to_base(np.zeros(6))] * 3)
    off = good.copy()
    off[1, 0, 0] += 2e-6  # |RᵀR − I| ≈ 4e-6 > 1e-6
    reflection = good.copy()
    reflection[2] = -reflection[2]
    nan = good.copy()
    nan[0, 1, 1] = np.nan
    for batch, index in ((off, 1), (reflection, 2), (nan, 0)):
        with pytest.raises(InvalidInput, match=rf"\[{index}\]|finite"):
            as_rotation_batch(batch)
        assert rotation_rows(batch[index]) is None
    as_rotation_batch(good)
    assert rotation_rows(good[0]) == good[0].tolist()
    nearly = good[0] + 1e-7 * rng.normal(size=(3, 3))  # within the tolerance: accepted by both
    assert rotation_rows(nearly) is not None and as_rotation_batch(nearly)[0].shape == (1, 3, 3)
    with pytest.raises(InvalidInput, match="not a rotation"):
        Compensator(paper_like_truth()).compensate_rotation(off[1], np.zeros(6))


def test_compensate_rotation_fast_path_agrees_with_the_array_checks_at_the_tolerance(rng):
    """The float64 fast path of compensate_rotation accepts exactly what as_rotation_batch
    accepts.
    """
    compensator = Compensator(paper_like_truth())
    base = Arm.default().rotation_sensor_to_base(np.array([0.1, 0.2, -0.6, 0.3, -1.0, 0.2]))
    raw = np.array([1.0, -2.0, 3.0, 0.1, -0.2, 0.3])
    accepted = refused = 0
    for scale in (3e-7, 5e-7, 1e-6):  # perturbations straddling |RᵀR − I| = 1e-6
        for _ in range(100):
            candidate = base + scale * rng.normal(size=(3, 3))
            try:
                as_rotation_batch(candidate)
            except InvalidInput as error:
                refused += 1
                with pytest.raises(InvalidInput) as fast:
                    compensator.compensate_rotation(candidate, raw)
                assert str(fast.value) == str(error)
            else:
                accepted += 1
                expected = compensator.compensate_unchecked(candidate, raw)
                np.testing.assert_allclose(
                    compensator.compensate_rotation(candidate, raw),
                    expected,
                    rtol=1e-12,
                    atol=1e-12,
                )
                np.testing.assert_allclose(
                    compensator.compensate_rotation(candidate.tolist(), raw.tolist()),
                    expected,
                    rtol=1e-12,
                    atol=1e-12,
                )
    assert accepted > 20 and refused > 20
    for bad_raw in ([np.nan, 0, 0, 0, 0, 0], [np.inf, 0, 0, 0, 0, 0]):
        with pytest.raises(InvalidInput, match="finite"):
            compensator.compensate_rotation(base, np.array(bad_raw))
    with pytest.raises(InvalidInput, match="shape"):
        compensator.compensate_rotation(base, np.zeros(5))


def test_replaced_bias_reaches_the_float_path(arm):
    truth = paper_like_truth()
    compensator = Compensator(truth, arm)
    q, raw = np.zeros(6), truth.predict(arm.rotation_sensor_to_base(np.zeros(6)))
    compensator._bias = compensator._bias + [1.0, 0, 0, 0, 0, 0]
    compensator.refresh_floats()
    np.testing.assert_allclose(compensator.compensate(q, raw), [-1.0, 0, 0, 0, 0, 0], atol=1e-12)


def test_blocked_batch_compensation_equals_the_formula_over_several_blocks(arm, rng):
    from ftkin.calibration.model import _BLOCK

    truth = paper_like_truth()
    compensator = Compensator(truth, arm)
    count = 2 * _BLOCK + 11
    rotations = arm.rotation_sensor_to_base(arm.random_configurations(count, rng))
    raw = rng.normal(size=(count, 6)) * 5.0
    gravity = np.einsum("nji,j->ni", rotations, truth.gravity_in_base)
    bias = rng.normal(size=(count, 6))  # one bias per sample (as a drift model gives)
    for given, offsets in ((None, truth.bias), (bias, bias)):
        expected = raw - offsets
        expected[:, :3] -= gravity
        expected[:, 3:] -= np.cross(truth.center_of_mass, gravity)
        got = compensator._contact_batch(raw, gravity, given)
        np.testing.assert_allclose(got, expected, rtol=0, atol=1e-12)


@pytest.mark.parametrize(
    ("rotation_shape", "raw_shape"),
    [
        ((9,), (6,)),
        ((3, 3, 1), (6,)),
        ((3, 3), (5,)),
        ((3, 3), (6, 1)),
        ((3,), (6,)),
        ((), (6,)),
        ((2, 3, 3), (6,)),
    ],
)
def test_compensate_rotation_refuses_wrong_shapes_of_float_arrays(rotation_shape, raw_shape):
    rotation = np.float64(1.0) if rotation_shape == () else np.resize(np.eye(3), rotation_shape)
    with pytest.raises(InvalidInput, match="shape|compensate_batch|rotation"):
        Compensator(paper_like_truth()).compensate_rotation(rotation, np.ones(raw_shape))


def test_compensate_rotation_takes_a_batch_of_one_like_one_sample():
    compensator, rotation, raw = (
        Compensator(paper_like_truth()),
        np.eye(3)[[1, 2, 0]],
        np.arange(6.0),
    )
    expected = compensator.compensate_unchecked(rotation, raw)
    np.testing.assert_allclose(
        compensator.compensate_rotation(rotation[np.newaxis], raw), expected, rtol=1e-12, atol=1e-12
    )
    np.testing.assert_allclose(
        compensator.compensate_rotation(rotation, raw[np.newaxis]), expected, rtol=1e-12, atol=1e-12
    )
    np.testing.assert_allclose(
        compensator.compensate_rotation(rotation.astype(np.float32), raw.astype(int)),
        expected,
        rtol=1e-12,
        atol=1e-12,
    )


@pytest.mark.parametrize("length", [5, 7])
def test_signed_float_kernel_refuses_a_reading_of_another_length(length):
    """Regression: the kernel of a calibration with reading signs zipped the reading with the six
    signs, so seven values were cut to six without a word (and the zip was slower than unpacking).
    """
    from dataclasses import replace

    from ftkin import CalibrationResult

    truth = CalibrationResult.from_model(paper_like_truth())
    signed = Compensator(replace(truth, sensor_sign=-1, flip_axis="y"))
    rows, raw = np.eye(3).tolist(), np.arange(6.0)
    np.testing.assert_allclose(
        signed.contact_floats(rows, raw.tolist()),
        Compensator(truth).contact_floats(rows, (raw * signed.calibration.reading_signs).tolist()),
        rtol=1e-12,
        atol=1e-12,
    )
    with pytest.raises(ValueError):
        signed.contact_floats(rows, np.arange(float(length)).tolist())
