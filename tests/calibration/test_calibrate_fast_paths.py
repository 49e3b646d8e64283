"""The fast paths of ``calibrate()``'s default fit (issue 38: 12 poses within 5 ms).

Each skips or replaces work without changing what it decides; each is checked against an
independent computation:

* :func:`~ftkin.calibration.ml.gauss_newton` (the Gaussian fit without scipy's overhead): the
  first-order optimality condition ``Jᵀr = 0`` at its answer, scipy's ``least_squares`` at tight
  tolerances, and its rule for a rising cost on both sides of
  :data:`~ftkin.calibration.ml.COST_ROUNDING` (a one-parameter problem worked by hand);
* :func:`~ftkin.calibration.orientation_mistakes.cannot_name_a_mistake` (the doctor's other
  readings skipped): its bound on both sides of ``MISTAKE_RATIO``, the inequality it rests on for
  random weights, and the doctor run in full (the reference) on data around the ratio;
* the two-step fit shared by the convention check and the ``ml`` start, and the sign check's
  force steps of the four axis alternatives solved together (numpy's least squares per set).
"""

from __future__ import annotations

import re
from dataclasses import replace

import numpy as np
import pytest
from scipy.optimize import least_squares

from ftkin import ConventionMistake, Samples, SensorNoise, SimulatedSensor, calibrate
from ftkin.calibration import doctor, ml, orientation_mistakes
from ftkin.calibration.conventions import detect_sign_and_handedness
from ftkin.calibration.doctor import MISTAKE_RATIO, Reading, ReadingFit, diagnose_readings
from ftkin.calibration.linear import fit_linear
from ftkin.calibration.ml import COST_ROUNDING, WeightedProblem, fit_ml, gauss_newton
from ftkin.calibration.mount import YAW_START_GRID, force_step_cost, force_step_costs
from ftkin.calibration.orientation_mistakes import (
    MATRIX_TRANSPOSED,
    cannot_name_a_mistake,
    orientation_readings,
    refuse_orientation_mistakes,
)
from ftkin.kinematics.rotations import euler_zyx_to_matrix

NOISE = SensorNoise(0.03, 0.0015)  # per reading [N], [N·m]


def _poses(tool, rotations, seed: int, readings: int = 1):
    rng = np.random.default_rng(seed)
    return SimulatedSensor(tool, NOISE).samples(rotations, rng, readings).pose_averages()


# ------------------------------------------------------------------ Gauss–Newton
@pytest.mark.parametrize("seed", range(6))
def test_gauss_newton_reaches_the_minimum(tool, rotations, seed):
    """At its answer the scaled gradient ``Jᵀr`` vanishes to rounding, and scipy's
    Levenberg–Marquardt at its tightest tolerances lands within a millionth of a standard error.
    """
    poses = _poses(tool, rotations, seed)
    problem = WeightedProblem(poses.rotations, poses.wrenches, poses.counts, NOISE.channel_std)
    start = fit_linear(poses).to_vector()
    solved = gauss_newton(problem, start)
    assert solved is not None
    theta, evaluations = solved
    assert evaluations <= 8  # a few steps from the linear start (1e-4, 1e-7, 1e-10, 1e-13)
    jacobian, residuals = problem.whitened_jacobian(theta), problem.whitened_residuals(theta)
    scale = np.linalg.norm(jacobian, axis=0)
    gradient = (jacobian / scale).T @ residuals
    assert np.max(np.abs(gradient)) <= 1e-9 * np.linalg.norm(residuals)
    reference = least_squares(
        problem.whitened_residuals,
        start,
        jac=lambda x: -problem.whitened_jacobian(x),
        method="lm",
        x_scale="jac",
        xtol=1e-15,
        ftol=1e-15,
        gtol=1e-15,
    ).x
    standard_error = np.sqrt(np.diag(np.linalg.inv(jacobian.T @ jacobian)))
    np.testing.assert_array_less(np.abs(theta - reference), 1e-6 * standard_error)


def test_the_gaussian_fit_needs_no_scipy_solver(tool, rotations, monkeypatch):
    """The default fit (noise from the residuals: two solves) never reaches ``least_squares``;
    a robust loss still does."""
    import scipy.optimize

    calls = []
    real = scipy.optimize.least_squares

    def spy(*args, **kwargs):
        calls.append(kwargs.get("loss", "linear"))
        return real(*args, **kwargs)

    monkeypatch.setattr(scipy.optimize, "least_squares", spy)
    poses = _poses(tool, rotations, 0)
    fit = fit_ml(poses)
    assert fit.noise_source == "residuals" and calls == []
    fit_ml(poses, loss="soft_l1")
    assert calls and set(calls) == {"soft_l1"}


class _Line:
    """``prediction(x) = x`` of one reading ``0`` (cost ``x²``), with a Jacobian that claims
    slope ``slope``: a step from ``x`` lands at ``x (1 − 1/slope)``, its cost ``(1 − 1/slope)²``
    times the last."""

    def __init__(self, slope: float):
        self.slope, self.evaluations = slope, 0

    def whitened_residuals(self, x):
        self.evaluations += 1
        return np.array([0.0 - x[0]])

    def whitened_jacobian(self, x):
        return np.array([[self.slope]])


@pytest.mark.parametrize(
    "rise, gives_up", [(0.25 * COST_ROUNDING, False), (4.0 * COST_ROUNDING, True)]
)
def test_a_rise_within_rounding_is_no_divergence(rise, gives_up):
    """A step whose cost rises by ``rise`` (relative): within :data:`COST_ROUNDING` the steps go
    on (here they cycle, so the step budget ends them), beyond it the first step gives up."""
    slope = 1.0 / (1.0 + np.sqrt(1.0 + rise))  # (1 − 1/slope)² = 1 + rise
    problem = _Line(slope)
    assert gauss_newton(problem, np.array([1.0])) is None
    first_step_only = problem.evaluations == 2
    assert first_step_only == gives_up
    if not gives_up:
        assert problem.evaluations == ml.GAUSS_NEWTON_STEPS + 1


def test_a_diverging_start_is_left_to_scipy(tool, rotations):
    """Undamped steps from a start with the tool weight reversed raise the cost; ``_solve``
    then finds the minimum Levenberg–Marquardt finds."""
    poses = _poses(tool, rotations, 3)
    problem = WeightedProblem(poses.rotations, poses.wrenches, poses.counts, NOISE.channel_std)
    good = fit_linear(poses).to_vector()
    bad = good.copy()
    bad[0:3] *= -1.0  # the weight upside down
    bad[9:12] = [5.0, -5.0, 5.0]  # the centre of mass metres away [m]
    if gauss_newton(problem, bad) is not None:
        pytest.skip("Gauss–Newton converged from this start")
    theta, _ = ml._solve(problem, bad, "linear")
    reference = gauss_newton(problem, good)[0]
    np.testing.assert_allclose(theta, reference, rtol=1e-7, atol=1e-9)


def test_a_singular_step_is_left_to_scipy():
    """A Jacobian with a column of zeros (a parameter nothing depends on): no normal-equation
    step exists, and Gauss–Newton hands the fit over rather than guess."""

    class Flat(_Line):
        def whitened_jacobian(self, x):
            return np.array([[1.0, 0.0]])

    assert gauss_newton(Flat(1.0), np.array([1.0, 0.0])) is None


@pytest.mark.parametrize("mode", ["none", "full"])
def test_hat_blocks_are_the_projection_onto_the_jacobians_columns(tool, rotations, mode):
    """The per-pose blocks of ``J (JᵀJ)⁺ Jᵀ`` against ``Q Qᵀ`` of a QR factorization (full rank)
    and against numpy's SVD-based ``pinv`` with a column repeated (rank deficient)."""
    poses = _poses(tool, rotations, 6)
    problem = WeightedProblem(
        poses.rotations, poses.wrenches, poses.counts, NOISE.channel_std, mode=mode
    )
    x = np.concatenate([fit_linear(poses).to_vector(), np.zeros(problem.parameter_count - 12)])
    jacobian = problem.whitened_jacobian(x)
    q, _ = np.linalg.qr(jacobian)
    blocks = q.reshape(-1, 6, q.shape[1])
    expected = blocks @ np.transpose(blocks, (0, 2, 1))
    np.testing.assert_allclose(problem.hat_blocks(x), expected, rtol=0, atol=1e-10)

    class Repeated(WeightedProblem):  # the last column twice: rank one short
        def whitened_jacobian(self, x):
            full = super().whitened_jacobian(x)
            return np.concatenate([full, full[:, -1:]], axis=1)

    repeated = Repeated(poses.rotations, poses.wrenches, poses.counts, NOISE.channel_std, mode=mode)
    wide = repeated.whitened_jacobian(x)
    rows = wide.reshape(-1, 6, wide.shape[1])
    inverse = np.linalg.pinv(wide.T @ wide, rcond=1e-12)
    reference = rows @ inverse @ np.transpose(rows, (0, 2, 1))
    np.testing.assert_allclose(repeated.hat_blocks(x), reference, rtol=0, atol=1e-6)
    np.testing.assert_allclose(repeated.hat_blocks(x), expected, rtol=0, atol=1e-6)


# ------------------------------------------------------------------ the doctor's bound
def _fit(rss) -> ReadingFit:
    return ReadingFit(Reading("r", "", None), None, np.asarray(rss, dtype=float))


@pytest.mark.parametrize(
    "factor, decided", [(MISTAKE_RATIO * (1 - 1e-9), True), (MISTAKE_RATIO, False)]
)
def test_the_bound_on_both_sides_of_the_mistake_ratio(factor, decided):
    given = np.array([1.0, 2.0, 3.0, 0.1, 0.2, 0.3])
    alternative = given.copy()
    alternative[4] /= factor  # one channel fits `factor` times better
    assert cannot_name_a_mistake([_fit(given), _fit(alternative)]) is decided


def test_the_bound_asks_the_doctor_when_it_cannot_tell():
    given = np.ones(6)
    failed = ReadingFit(Reading("r", "", None), None, None, failure="cannot")
    assert cannot_name_a_mistake([_fit(given), failed])  # a failed reading is never named
    assert not cannot_name_a_mistake([failed, _fit(given)])  # the data as given do not fit
    assert not cannot_name_a_mistake([_fit(np.zeros(6)), _fit(np.zeros(6))])  # 0/0
    exact = np.ones(6)
    exact[2] = 0.0
    assert not cannot_name_a_mistake([_fit(given), _fit(exact)])  # a channel fits exactly


def test_a_weighted_ratio_never_exceeds_the_largest_channel_ratio():
    """The inequality the bound rests on, for the doctor's chi-squares (one positive variance
    per channel, any): ``Σ g/v ÷ Σ a/v ≤ max g/a``."""
    rng = np.random.default_rng(1)
    for _ in range(2000):
        given, alternative = rng.lognormal(0, 3, 6), rng.lognormal(0, 3, 6)
        variance = rng.lognormal(0, 6, 6)
        ratio = np.sum(given / variance) / np.sum(alternative / variance)
        assert ratio <= np.max(given / alternative) * (1 + 1e-12)


def test_skipping_the_doctor_never_changes_its_verdict(tool):
    """Orientations given transposed (and correctly), the noise raised until the transposed
    reading's chi-square ratio falls from ~130 through 20 to ~1: calibrate's check refuses
    exactly when the full doctor (the reference, every reading fitted) names the transposed
    matrix, the bound skips the doctor only where it names nothing, and the sweep holds both
    sides of the ratio (refused, the doctor asked but not refusing, the doctor skipped)."""
    seen = set()
    for transposed in (True, False):
        for noise_scale in (30, 60, 100, 150, 300):
            rng = np.random.default_rng(noise_scale)
            angles = np.rad2deg(rng.uniform(-0.3, 0.3, (12, 3)))  # [deg] within 0.3 rad
            true = euler_zyx_to_matrix(angles).reshape(-1, 3, 3)
            noise = SensorNoise(0.03 * noise_scale, 0.0015 * noise_scale)
            wrenches = SimulatedSensor(tool, noise).samples(true, rng, 1).wrenches
            samples = Samples(wrenches, np.transpose(true, (0, 2, 1)) if transposed else true)
            readings = orientation_readings(samples)
            report = diagnose_readings(readings)
            named = (
                report.verdict == "mistake"
                and report.culprit.reading.name == (MATRIX_TRANSPOSED[0])
            )
            unchecked = [ReadingFit(r, None, doctor.unchecked_rss(r)) for r in readings[1:2]]
            skipped = cannot_name_a_mistake([doctor.fit_reading(readings[0]), *unchecked])
            assert not (skipped and named)
            seen.add("refused" if named else "skipped" if skipped else "asked")
            if named:
                with pytest.raises(ConventionMistake, match=re.escape(MATRIX_TRANSPOSED[0])):
                    refuse_orientation_mistakes(samples)
            else:
                refuse_orientation_mistakes(samples)
    assert seen == {"refused", "asked", "skipped"}


def test_the_unchecked_sums_of_squares_are_the_fits(tool, rotations):
    """Where the checks pass, :func:`unchecked_rss` is :func:`fit_reading`'s ``rss`` (with a
    unit scale and mixed-up channels too); where they fail (every pose alike), it gives a number
    that can only send the bound to the doctor, who does not name that reading."""
    poses = _poses(tool, rotations, 7)
    for reading in doctor.wrench_readings(poses, joints=False)[:6]:
        fitted = doctor.fit_reading(reading)
        if fitted.rss is not None:
            np.testing.assert_allclose(doctor.unchecked_rss(reading), fitted.rss, rtol=1e-10)
    same = replace(poses, rotations=np.repeat(poses.rotations[:1], len(poses), axis=0))
    alike = Reading("every pose alike", "", same)
    assert doctor.fit_reading(alike).rss is None  # refused by the checks: never named
    given = doctor.fit_reading(Reading("as given", "", poses))
    unchecked = ReadingFit(alike, None, doctor.unchecked_rss(alike))
    assert np.all(np.isfinite(unchecked.rss))
    if not cannot_name_a_mistake([given, unchecked]):  # asked: the doctor names no failed reading
        report = diagnose_readings([given.reading, alike])
        assert report.culprit is None or report.culprit.reading.name != alike.name


def test_clean_data_skip_the_doctor(tool, rotations, monkeypatch):
    """Orientations given correctly: the other readings are not fitted (the doctor's time
    was three quarters of ``calibrate``'s); given transposed, the doctor refuses them."""
    calls = []
    real = orientation_mistakes.diagnose_readings
    monkeypatch.setattr(
        orientation_mistakes,
        "diagnose_readings",
        lambda readings: calls.append(len(readings)) or real(readings),
    )
    rng = np.random.default_rng(2)
    samples = SimulatedSensor(tool, NOISE).samples(rotations, rng, 1)
    calibrate(samples)
    assert calls == []
    transposed = Samples(samples.wrenches, np.transpose(samples.rotations, (0, 2, 1)))
    with pytest.raises(ConventionMistake, match=re.escape(MATRIX_TRANSPOSED[0])):
        calibrate(transposed)
    assert calls


# ------------------------------------------------------------------ one two-step fit
def test_the_convention_checks_linear_fit_is_mls_start(tool, rotations, monkeypatch):
    """``ConventionCheck.linear_fit`` is the two-step fit of the readings; ``calibrate`` starts
    the ml fit from it rather than fitting it again, and the linear method returns it."""
    poses = _poses(tool, rotations, 4)
    check = detect_sign_and_handedness(poses)
    np.testing.assert_allclose(
        check.linear_fit.to_vector(), fit_linear(poses).to_vector(), rtol=1e-12, atol=0
    )
    samples = Samples(poses.wrenches, poses.rotations)
    expected = calibrate(samples)
    monkeypatch.setattr(ml, "fit_linear", lambda *a, **k: pytest.fail("fitted again"))
    np.testing.assert_allclose(expected.to_vector(), calibrate(samples).to_vector(), rtol=1e-12)
    np.testing.assert_allclose(
        calibrate(samples, method="linear").to_vector(),
        fit_linear(poses).to_vector(),
        rtol=1e-12,
    )


@pytest.mark.parametrize("mode", ["none", "yaw"])
def test_force_step_costs_of_several_sets_are_each_sets_own(tool, rotations, mode):
    """One factorization for the four axis alternatives of the sign check: each set's cost is
    its own least-squares residual (numpy, one set at a time, over the same yaw grid)."""
    poses = _poses(tool, rotations, 5)
    force_sets = np.array([poses.wrenches[:, :3] * signs for signs in ([1, 1, 1], [-1, 1, 1])])
    costs, mounts = force_step_costs(poses.rotations, force_sets, mode)
    grid = YAW_START_GRID if mode == "yaw" else [0.0]
    for forces, cost, mount in zip(force_sets, costs, mounts):
        expected = []
        for yaw in grid:
            turn = np.array(
                [[np.cos(yaw), -np.sin(yaw), 0], [np.sin(yaw), np.cos(yaw), 0], [0, 0, 1]]
            )
            turned = poses.rotations @ turn.T
            regressor = np.concatenate(
                [np.transpose(turned, (0, 2, 1)), np.broadcast_to(np.eye(3), turned.shape)], axis=2
            ).reshape(-1, 6)
            _, residual, *_ = np.linalg.lstsq(regressor, forces.reshape(-1), rcond=None)
            expected.append((float(residual[0]), turn))
        best_cost, best_turn = min(expected, key=lambda pair: pair[0])
        np.testing.assert_allclose(cost, best_cost, rtol=1e-9)
        np.testing.assert_allclose(mount, best_turn, atol=1e-12)
        assert force_step_cost(poses.rotations, forces, mode)[0] == pytest.approx(cost, rel=1e-12)
