"""Drift-robust pose order: the walk-integrated information against a dense GLS, the search, plan
and CLI.
"""

from __future__ import annotations

import numpy as np
import pytest

from ftkin.calibration.information import (
    SensorNoise,
    covariance_from_information,
    fisher_information,
)
from ftkin.calibration.random_walk import walk_gains
from ftkin.cli import main
from ftkin.exceptions import InvalidInput
from ftkin.planning.drift_order import drift_robust_order, walk_information
from ftkin.planning.evaluation import evaluate_poses, expected_tool
from ftkin.planning.plan import plan_poses

RATE = np.repeat([0.002, 4e-5], 3)  # [N/√s, N·m/√s]
NOISE = SensorNoise(0.03, 0.0015)
INTERVAL, READINGS = 30.0, 10  # [s], readings per pose


def dense_information(model, rotations, interval, readings, rate, noise) -> np.ndarray:
    """``Σ_c J_cᵀ Σ_c⁻¹ J_c`` with the full covariance of each channel: white noise plus a walk
    anchored at the end.
    """
    count = len(rotations)
    times = np.arange(count) * interval
    to_end = times[-1] - times
    jacobian = model.parameter_jacobian(rotations)
    information = np.zeros((12, 12))
    for channel in range(6):
        covariance = rate[channel] ** 2 * np.minimum.outer(to_end, to_end)
        covariance += np.eye(count) * noise.channel_std[channel] ** 2 / readings
        rows = jacobian[:, channel, :]
        information += rows.T @ np.linalg.solve(covariance, rows)
    return information


@pytest.fixture(scope="module")
def pose_set(arm):
    rng = np.random.default_rng(5)
    return arm.rotation_sensor_to_base(arm.random_configurations(24, rng, margin=0.3))


def test_walk_information_matches_dense_gls(pose_set):
    model = expected_tool(15.0, [0.03, -0.02, 0.08])
    gains = walk_gains(
        np.arange(len(pose_set)) * INTERVAL,
        np.tile(NOISE.channel_std**2 / READINGS, (len(pose_set), 1)),
        RATE,
    )
    fast = walk_information(model.parameter_jacobian(pose_set), gains)
    dense = dense_information(model, pose_set, INTERVAL, READINGS, RATE, NOISE)
    np.testing.assert_allclose(fast, dense, rtol=1e-7, atol=1e-9 * np.max(np.abs(dense)))
    # batched over candidate orders: each slice is its own order
    orders = np.array([np.arange(len(pose_set)), np.arange(len(pose_set))[::-1]])
    batch = walk_information(model.parameter_jacobian(pose_set)[orders], gains)
    reverse = dense_information(model, pose_set[::-1], INTERVAL, READINGS, RATE, NOISE)
    np.testing.assert_allclose(batch[1], reverse, rtol=1e-7, atol=1e-9 * np.max(np.abs(reverse)))


def test_order_is_a_permutation_that_beats_a_random_order_and_is_reproducible(pose_set):
    model = expected_tool(15.0, [0.03, -0.02, 0.08])
    options = dict(
        rate=RATE, noise_std=NOISE.channel_std, readings_per_pose=READINGS, pose_interval=INTERVAL
    )
    order, value = drift_robust_order(model, pose_set, rng=np.random.default_rng(1), **options)
    again, _ = drift_robust_order(model, pose_set, rng=np.random.default_rng(1), **options)
    assert sorted(order.tolist()) == list(range(len(pose_set)))
    np.testing.assert_array_equal(order, again)
    dense = dense_information(model, pose_set[order], INTERVAL, READINGS, RATE, NOISE)
    assert value == pytest.approx(np.linalg.slogdet(dense)[1], rel=1e-9)
    given = np.linalg.slogdet(dense_information(model, pose_set, INTERVAL, READINGS, RATE, NOISE))[
        1
    ]
    assert value > given
    # what it is for: the weight's standard error with the drift comes closer to the drift-free one
    free = covariance_from_information(fisher_information(model, pose_set, NOISE, READINGS))

    def weight_std(rotations):
        return evaluate_poses(
            rotations,
            tool_weight=15.0,
            center_of_mass=[0.03, -0.02, 0.08],
            noise=NOISE,
            readings_per_pose=READINGS,
            drift_rate=[0.002, 4e-5],
            pose_interval=INTERVAL,
        ).standard_errors["tool_weight"]

    floor = evaluate_poses(
        pose_set,
        tool_weight=15.0,
        center_of_mass=[0.03, -0.02, 0.08],
        noise=NOISE,
        readings_per_pose=READINGS,
    ).standard_errors["tool_weight"]
    assert free.shape == (12, 12)
    assert floor < weight_std(pose_set[order]) < weight_std(pose_set)


def test_negligible_drift_predicts_the_constant_bias_errors(pose_set):
    common = dict(tool_weight=15.0, noise=NOISE, readings_per_pose=READINGS)
    constant = evaluate_poses(pose_set, **common)
    drifting = evaluate_poses(pose_set, drift_rate=[1e-12, 1e-14], pose_interval=INTERVAL, **common)
    np.testing.assert_allclose(drifting.vector_std, constant.vector_std, rtol=1e-6)
    assert "random walk" in drifting.report() and "random walk" not in constant.report()


@pytest.mark.parametrize(
    "rate", [[0.002], [0.002, 4e-5, 1.0], [-0.002, 4e-5], [0.0, 0.0], [np.nan, 1e-5], [1e3, 1.0]]
)
def test_bad_drift_rates_are_refused(pose_set, rate):
    with pytest.raises(InvalidInput, match="drift_rate"):
        evaluate_poses(pose_set, drift_rate=rate)


def test_drift_and_mount_cannot_be_planned_together(arm, pose_set):
    with pytest.raises(InvalidInput, match="drift.*mount"):
        evaluate_poses(pose_set, drift_rate=[0.002, 4e-5], estimate_mount="yaw")
    with pytest.raises(InvalidInput, match="drift.*mount"):
        plan_poses(arm, 8, drift_rate=[0.002, 4e-5], estimate_mount="yaw", candidates=200)
    with pytest.raises(InvalidInput, match="pose_interval"):
        plan_poses(arm, 8, drift_rate=[0.002, 4e-5], pose_interval=-1.0, candidates=200)


def test_plan_with_drift_reorders_the_same_poses(arm):
    common = dict(seed=2, candidates=400, tool_weight=15.0, noise=NOISE, readings_per_pose=READINGS)
    travel = plan_poses(arm, 10, **common)
    robust = plan_poses(arm, 10, drift_rate=[0.002, 4e-5], pose_interval=INTERVAL, **common)
    as_set = {tuple(np.round(q, 12)) for q in travel.joint_positions}
    assert {tuple(np.round(q, 12)) for q in robust.joint_positions} == as_set
    assert "random walk" in robust.criterion
    walk_of_travel = evaluate_poses(
        travel.rotations,
        tool_weight=15.0,
        noise=NOISE,
        readings_per_pose=READINGS,
        drift_rate=[0.002, 4e-5],
        pose_interval=INTERVAL,
    )
    assert robust.criterion_value >= np.linalg.slogdet(walk_of_travel.information)[1] - 1e-9
    np.testing.assert_allclose(robust.evaluation.drift_rate, [0.002, 4e-5])


def test_more_readings_per_pose_plan_as_well_with_smaller_errors(arm):
    """D-optimality is blind to a common scale of the information (100 readings per pose:
    information ~1e9).

    This used to fail: an absolute ridge made the first greedy steps singular.
    The designs may differ among near-equivalent ones (the arm's symmetries),
    but the criterion moves by exactly ``12 log 100`` and the errors by 10×.
    """
    one = plan_poses(arm, 12, seed=1, candidates=400)
    many = plan_poses(
        arm, 12, seed=1, candidates=400, readings_per_pose=100, noise=SensorNoise(0.02, 0.002)
    )
    assert many.criterion_value - one.criterion_value == pytest.approx(12 * np.log(100.0), abs=0.05)
    ratio = one.standard_errors["tool_weight"] / many.standard_errors["tool_weight"]
    assert ratio == pytest.approx(10.0, rel=0.05)
    quiet = plan_poses(arm, 12, seed=1, candidates=400, noise=SensorNoise(1e-5, 1e-6))
    assert np.isfinite(quiet.criterion_value)


def test_cli_plan_with_drift(tmp_path, capsys):
    out = tmp_path / "poses.json"
    assert (
        main(
            [
                "plan",
                "--n",
                "6",
                "--drift-rate",
                "0.002",
                "4e-5",
                "--pose-interval",
                "20",
                "--seed",
                "1",
                "-o",
                str(out),
            ]
        )
        == 0
    )
    text = capsys.readouterr().out
    assert "random walk of 0.002 N/√s" in text and "one every 20 s" in text
    assert '"drift_rate": [\n    0.002,\n    4e-05\n  ]' in out.read_text()
    assert main(["plan", "--n", "6", "--drift-rate", "0", "0"]) == 2
    assert "drift_rate must be two finite rates" in capsys.readouterr().err


def test_pose_times_replace_the_interval(pose_set, tmp_path, capsys):
    common = dict(
        tool_weight=15.0, noise=NOISE, readings_per_pose=READINGS, drift_rate=[0.002, 4e-5]
    )
    uniform = evaluate_poses(pose_set, pose_interval=INTERVAL, **common)
    timed = evaluate_poses(
        pose_set, pose_times=100.0 + INTERVAL * np.arange(len(pose_set)), **common
    )
    np.testing.assert_allclose(
        timed.vector_std, uniform.vector_std, rtol=1e-12
    )  # only differences of times matter
    assert "poses at their times (100 to" in timed.report()
    uneven = 30.0 * np.arange(len(pose_set)) ** 1.5
    to_end = uneven[-1] - uneven
    jacobian = expected_tool(15.0).parameter_jacobian(pose_set)
    dense = sum(
        jacobian[:, c].T
        @ np.linalg.solve(
            RATE[c] ** 2 * np.minimum.outer(to_end, to_end)
            + np.eye(len(uneven)) * NOISE.channel_std[c] ** 2 / READINGS,
            jacobian[:, c],
        )
        for c in range(6)
    )
    np.testing.assert_allclose(
        evaluate_poses(pose_set, pose_times=uneven, **common).information,
        dense,
        rtol=1e-7,
        atol=1e-9 * np.max(np.abs(dense)),
    )
    with pytest.raises(InvalidInput, match="strictly increasing"):
        evaluate_poses(pose_set, pose_times=np.zeros(len(pose_set)), **common)
    # the CLI takes the times of a recording's time column
    path = tmp_path / "poses.csv"
    path.write_text(
        "t,alpha,beta,gamma\n"
        + "".join(
            f"{30 * i},{a},{b},0\n"
            for i, (a, b) in enumerate([(0, 0), (90, 0), (0, 90), (180, 0), (0, -90), (45, 45)])
        )
    )
    assert main(["evaluate-poses", str(path), "--drift-rate", "0.002", "4e-5"]) == 0
    assert "poses at their times (0 to 150 s)" in capsys.readouterr().out
    assert main(["evaluate-poses", str(path), "--pose-interval", "5"]) == 2
    assert "pose_interval (5.0 s) applies with drift_rate" in capsys.readouterr().err


def test_the_travel_bound_is_kept(arm, pose_set):
    common = dict(
        seed=2,
        candidates=400,
        tool_weight=15.0,
        noise=NOISE,
        readings_per_pose=READINGS,
        drift_rate=[0.002, 4e-5],
        pose_interval=INTERVAL,
    )
    travel = plan_poses(
        arm, 10, **{k: v for k, v in common.items() if k not in ("drift_rate", "pose_interval")}
    )
    free = plan_poses(arm, 10, **common)
    bounded = plan_poses(arm, 10, max_travel_ratio=1.2, **common)
    # independent: the path length from the joint positions themselves
    length = float(np.sum(np.linalg.norm(np.diff(bounded.joint_positions, axis=0), axis=1)))
    assert bounded.joint_travel == pytest.approx(length)
    assert length <= 1.2 * travel.joint_travel * (1 + 1e-9) < free.joint_travel
    assert free.criterion_value >= bounded.criterion_value
    assert f"joint travel along the visiting order: {length:.1f} rad" in bounded.report()
    with pytest.raises(InvalidInput, match="applies with drift_rate"):
        plan_poses(arm, 8, max_travel_ratio=1.5, candidates=200)
    with pytest.raises(InvalidInput, match="max_travel_ratio must be between 1 and 100"):
        plan_poses(arm, 8, drift_rate=[0.002, 4e-5], max_travel_ratio=0.9, candidates=200)
    model = expected_tool(15.0)
    with pytest.raises(InvalidInput, match="needs the distances"):
        drift_robust_order(
            model,
            pose_set,
            rate=RATE,
            noise_std=NOISE.channel_std,
            readings_per_pose=READINGS,
            pose_interval=INTERVAL,
            rng=np.random.default_rng(0),
            max_length=10.0,
        )


def test_a_pose_interval_without_a_drift_rate_is_refused_by_the_library_as_by_the_cli(
    pose_set, capsys
):
    """The interval matters only to a drift: ExpectedCalibration refuses it alone (the API
    silently dropped it, the CLI refused it), and ``plan``/``evaluate-poses`` say the same."""
    import dataclasses

    from ftkin.planning.evaluation import ExpectedCalibration

    with pytest.raises(InvalidInput) as refused:
        ExpectedCalibration(tool_weight=15.0, pose_interval=5.0)
    text = str(refused.value)
    assert text.startswith("pose_interval (5.0 s) applies with drift_rate")
    with pytest.raises(InvalidInput, match=r"pose_interval \(5.0 s\) applies with drift_rate"):
        evaluate_poses(pose_set, pose_interval=5.0)
    assert main(["plan", "--n", "8", "--pose-interval", "5"]) == 2
    assert text in capsys.readouterr().err
    # given with a rate it is kept; a rate alone takes the documented 10 s; without a rate None,
    # so that a copy of an expectation without a drift is valid
    assert ExpectedCalibration(drift_rate=[0.002, 4e-5], pose_interval=5.0).pose_interval == 5.0
    assert ExpectedCalibration(drift_rate=[0.002, 4e-5]).pose_interval == 10.0
    plain = ExpectedCalibration(tool_weight=15.0)
    assert plain.pose_interval is None
    assert dataclasses.replace(plain, tool_weight=2.0).model.tool_weight == pytest.approx(2.0)
