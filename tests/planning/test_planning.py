"""Pose planning: constraints met (checked independently), predictions vs Monte-Carlo, determinism,
errors, CLI.
"""

from __future__ import annotations

import argparse
import itertools
import json

import numpy as np
import pinocchio as pin
import pytest

from ftkin import calibrate
from ftkin.calibration.fit_options import METHODS
from ftkin.calibration.information import SensorNoise
from ftkin.cli import main
from ftkin.exceptions import InvalidInput, UnobservableParameters
from ftkin.kinematics.collision import SelfCollision
from ftkin.planning.design import d_optimal_selection, information_factors, log_det
from ftkin.planning.evaluation import evaluate_poses
from ftkin.planning.order import (
    joint_distances,
    path_length,
    revolute_mask,
    short_travel_order,
    unwind_revolute,
)
from ftkin.planning.plan import plan_poses
from ftkin.sim.paper import paper_samples
from ftkin.sim.sensor import SimulatedSensor, paper_like_truth

FLOOR = 0.25  # [m]
MAX_TILT = np.deg2rad(70.0)
MARGIN = 0.1  # [rad]
JOINT1_RANGE = (-1.2, 1.5)  # [rad]


@pytest.fixture(scope="module")
def constrained_plan(arm):
    return plan_poses(
        arm,
        9,
        margin=MARGIN,
        floor_height=FLOOR,
        max_tilt=MAX_TILT,
        joint_ranges={"joint1": JOINT1_RANGE},
        seed=3,
        candidates=1500,
    )


@pytest.fixture(scope="module")
def plan(arm):
    truth = paper_like_truth()
    return plan_poses(
        arm,
        8,
        tool_weight=truth.tool_weight,
        center_of_mass=truth.center_of_mass,
        seed=1,
        candidates=1500,
    )


def independent_collision_check(arm):
    """A collision checker built from the URDF here, without ftkin.kinematics.collision: adjacency
    by the joint tree.
    """
    model, geometry, _ = pin.buildModelsFromUrdf(str(arm.urdf_path))
    geometry.addAllCollisionPairs()
    objects = geometry.geometryObjects
    for pair in [(p.first, p.second) for p in geometry.collisionPairs]:
        a, b = objects[pair[0]].parentJoint, objects[pair[1]].parentJoint
        if a == b or model.parents[a] == b or model.parents[b] == a:
            geometry.removeCollisionPair(pin.CollisionPair(*pair))
    data, geometry_data = model.createData(), pin.GeometryData(geometry)

    def collides(q):
        return pin.computeCollisions(model, data, geometry, geometry_data, q, False)

    return collides


def test_planned_poses_meet_every_constraint(arm, constrained_plan, rng):
    q = constrained_plan.joint_positions
    assert q.shape == (9, arm.nq)
    assert np.all(q >= arm.lower_limits + MARGIN - 1e-12) and np.all(
        q <= arm.upper_limits - MARGIN + 1e-12
    )
    assert np.all(q[:, 0] >= JOINT1_RANGE[0]) and np.all(q[:, 0] <= JOINT1_RANGE[1])
    collides = independent_collision_check(arm)
    # The independent checker does find collisions among random configurations (so it can fail).
    assert any(collides(x) for x in arm.random_configurations(300, rng))
    for x in q:
        assert not collides(x)
        for frame in ("sensor", "tool"):
            assert arm.frame_placement(x, frame)[1][2] >= FLOOR
        tool_z_axis = arm.frame_placement(x, "tool")[0][:, 2]
        assert np.arccos(-tool_z_axis[2]) <= MAX_TILT + 1e-9
    np.testing.assert_allclose(
        constrained_plan.rotations, arm.rotation_sensor_to_base(q), atol=1e-12
    )


def test_predicted_standard_errors_match_monte_carlo(arm, plan):
    truth = paper_like_truth()
    noise = SensorNoise.paper()
    sensor = SimulatedSensor(truth, noise)
    rng = np.random.default_rng(7)
    method = "ml" if "ml" in METHODS else METHODS[0]
    estimates = np.array(
        [
            calibrate(
                sensor.samples_at_configurations(arm, plan.joint_positions, rng), method=method
            ).to_vector()
            for _ in range(400)
        ]
    )
    observed = estimates.std(axis=0, ddof=1)
    predicted = plan.evaluation.vector_std
    if method == "ml":
        compared = np.arange(12)
    else:
        # The two-step linear estimator is not efficient: its gravity and COM errors exceed the
        # Fisher bound; the biases (what a planned set pins to σ/√N) must still match.
        compared = np.arange(3, 9)
    np.testing.assert_allclose(observed[compared], predicted[compared], rtol=0.2)
    # The estimator's mean is the truth (no bias larger than three standard errors of the mean).
    assert np.all(
        np.abs(estimates.mean(axis=0) - truth.to_vector()) < 3 * observed / np.sqrt(400) + 1e-12
    )


def test_planned_set_beats_the_papers_nine(arm, plan):
    paper = evaluate_poses(paper_samples().rotations)
    nine = plan_poses(arm, 9, seed=0, candidates=1500)
    assert np.all(nine.evaluation.vector_std <= paper.vector_std)
    np.testing.assert_allclose(
        nine.evaluation.vector_std[3:9], nine.evaluation.bias_bound, rtol=0.05
    )


def test_same_seed_same_plan(arm, plan):
    truth = paper_like_truth()
    again = plan_poses(
        arm,
        8,
        tool_weight=truth.tool_weight,
        center_of_mass=truth.center_of_mass,
        seed=1,
        candidates=1500,
    )
    np.testing.assert_allclose(again.joint_positions, plan.joint_positions, rtol=1e-12, atol=1e-15)
    other = plan_poses(
        arm,
        8,
        tool_weight=truth.tool_weight,
        center_of_mass=truth.center_of_mass,
        seed=2,
        candidates=1500,
    )
    assert not np.array_equal(other.joint_positions, plan.joint_positions)


def test_fewer_than_three_poses_refused(arm):
    with pytest.raises(UnobservableParameters, match="at least 3"):
        plan_poses(arm, 2)
    with pytest.raises(InvalidInput, match="integer"):
        plan_poses(arm, 3.5)


def test_tilt_limit_zero_names_the_unobservable_parameters(arm):
    with pytest.raises(
        UnobservableParameters, match="tool axis within 0° of straight down"
    ) as caught:
        plan_poses(arm, 9, max_tilt=0.0)
    assert {"gravity_in_base[z]", "force_offset[z]", "center_of_mass[z]"} <= set(caught.value.names)


def test_impossible_floor_names_the_constraint(arm):
    with pytest.raises(InvalidInput, match=r"floor: 2000.*above 3 m"):
        plan_poses(arm, 9, floor_height=3.0, max_samples=2000)


def test_collision_pairs_follow_the_documented_rule(arm):
    checker = SelfCollision(arm)
    joint_of = {o.name: o.parentJoint for o in checker.geometry_model.geometryObjects}
    parents = arm.model.parents
    for first, second in checker.pair_names:
        a, b = joint_of[first], joint_of[second]
        assert a != b and parents[a] != b and parents[b] != a
    reasons = {(r.first, r.second): r.reason for r in checker.removed}
    assert reasons[("link5_0", "gripper_0")] == "adjacent links"
    assert (
        "link6_0",
        "gripper_1",
    ) not in checker.pair_names  # one rigid body (Pinocchio skips or we remove)
    assert reasons[("base_link_0", "link1_0")] == "adjacent links"
    assert ("link3_0", "gripper_0") in checker.pair_names


def test_d_optimal_selection_is_a_local_optimum_near_the_best(rng):
    rotations = np.array([pin.exp3(v) for v in rng.normal(size=(10, 3))])
    factors = information_factors(
        rotations, [0, 0, -3.15], [0, 0, 0.047], SensorNoise.paper().channel_std
    )
    chosen, value = d_optimal_selection(factors, 4)
    contributions = np.einsum("nki,nkj->nij", factors, factors)
    assert value == pytest.approx(log_det(contributions[chosen].sum(axis=0)))
    for slot, candidate in itertools.product(range(4), range(10)):
        if candidate in chosen:
            continue
        swapped = chosen.copy()
        swapped[slot] = candidate
        assert log_det(contributions[swapped].sum(axis=0)) <= value + 1e-9
    best = max(
        log_det(contributions[list(c)].sum(axis=0)) for c in itertools.combinations(range(10), 4)
    )
    assert value >= best - 0.5


def test_entrywise_cholesky_log_det_equals_lapack(rng):
    from ftkin.planning.design import _cholesky_log_det

    x = rng.normal(size=(500, 6, 12)) * rng.uniform(1e-3, 1e3, size=(500, 1, 1))
    matrices = x @ np.transpose(x, (0, 2, 1)) + np.eye(6)

    def entries(m):
        return np.ascontiguousarray(np.transpose(m, (1, 2, 0)))

    np.testing.assert_allclose(
        _cholesky_log_det(entries(matrices)), np.linalg.slogdet(matrices)[1], rtol=1e-12, atol=1e-12
    )
    huge = matrices[:3] * 1e120  # pivot product beyond the float range: sum of logs
    np.testing.assert_allclose(
        _cholesky_log_det(entries(huge)), np.linalg.slogdet(huge)[1], rtol=1e-12
    )
    matrices[7, 2, 2] = -1.0  # not positive definite
    assert _cholesky_log_det(entries(matrices)) is None


def test_exchange_gains_equal_the_log_det_increase(rng, monkeypatch):
    from ftkin.planning.design import _gains

    factors = rng.normal(size=(300, 6, 12))
    base = rng.normal(size=(30, 12))
    information = base.T @ base
    expected = [log_det(information + f.T @ f) - log_det(information) for f in factors]
    gains = _gains(np.ascontiguousarray(np.transpose(factors, (1, 2, 0))), information)
    np.testing.assert_allclose(gains, expected, rtol=1e-9, atol=1e-9)
    monkeypatch.setattr(
        "ftkin.planning.design._cholesky_log_det", lambda entries: None
    )  # the LU fallback
    np.testing.assert_allclose(
        _gains(np.ascontiguousarray(np.transpose(factors, (1, 2, 0))), information),
        expected,
        rtol=1e-9,
        atol=1e-9,
    )


def test_travel_order_close_to_brute_force(rng):
    q = rng.uniform(-2, 2, size=(7, 6))
    distances = joint_distances(q)
    order = short_travel_order(q)
    assert sorted(order) == list(range(7))
    best = min(path_length(distances, p) for p in itertools.permutations(range(7)))
    assert path_length(distances, order) <= 1.05 * best


def test_unwinding_keeps_the_pose(arm):
    lower, upper = arm.lower_limits, arm.upper_limits
    q = np.array(
        [0.1, -0.2, 0.5, 3.0, 0.3, 5.5]
    )  # joint6 allows ±2π: 5.5 rad is -0.78 rad a turn back
    unwound = unwind_revolute(q, lower, upper, revolute_mask(arm.model))
    np.testing.assert_allclose(unwound[:5], q[:5])
    assert unwound[5] == pytest.approx(5.5 - 2 * np.pi)
    np.testing.assert_allclose(
        arm.rotation_sensor_to_base(unwound), arm.rotation_sensor_to_base(q), atol=1e-12
    )


def test_cli_plan_then_evaluate(tmp_path, capsys):
    out = tmp_path / "poses.csv"
    assert main(["plan", "--n", "5", "-o", str(out), "--floor-height", "0.2", "--seed", "4"]) == 0
    planned = capsys.readouterr().out
    header = out.read_text().splitlines()[0].split(",")
    assert header == ["pose", "joint1", "joint2", "joint3", "joint4", "joint5", "joint6"]
    assert main(["evaluate-poses", str(out)]) == 0
    evaluated = capsys.readouterr().out
    table = lambda text: [
        line for line in text.splitlines() if line.startswith(("fx0", "mz0", "pz"))
    ]  # noqa: E731
    assert table(evaluated) == table(planned) and len(table(planned)) == 3


def test_cli_formats_and_orientation_columns(tmp_path, capsys, arm):
    path = tmp_path / "poses.json"
    assert (
        main(["plan", "--n", "4", "-o", str(path), "--seed", "1", "--readings-per-pose", "1"]) == 0
    )
    document = json.loads(path.read_text())
    q = np.array(document["joint_positions_rad"])
    rotations = arm.rotation_sensor_to_base(q)
    expected = evaluate_poses(rotations).standard_errors["force_offset"]
    np.testing.assert_allclose(document["predicted_standard_errors"]["force_offset"], expected)
    quaternions = np.array([pin.Quaternion(r).coeffs() for r in rotations])[:, [3, 0, 1, 2]]
    csv_path = tmp_path / "quaternions.csv"
    csv_path.write_text(
        "qw,qx,qy,qz\n"
        + "\n".join(",".join(repr(float(v)) for v in row) for row in quaternions)
        + "\n"
    )
    capsys.readouterr()
    assert main(["evaluate-poses", str(csv_path), "--readings-per-pose", "1"]) == 0
    assert f"{expected[0]:>14.3e}" in capsys.readouterr().out
    assert main(["plan", "--n", "2"]) == 2
    assert "at least 3" in capsys.readouterr().err


def test_bad_counts_and_seed_refused(arm):
    with pytest.raises(InvalidInput, match="seed must be at least 0, got -1"):
        plan_poses(arm, 4, seed=-1)
    with pytest.raises(InvalidInput, match="readings_per_pose must be an integer"):
        plan_poses(arm, 4, readings_per_pose=2.5)
    with pytest.raises(InvalidInput, match="readings_per_pose must be an integer"):
        evaluate_poses(paper_samples().rotations, readings_per_pose=0.5)
    with pytest.raises(InvalidInput, match="noise must be an ftkin.SensorNoise"):
        evaluate_poses(paper_samples().rotations, noise=0.02)


def test_cli_plan_refusals(capsys):
    assert main(["plan", "--n", "4", "--format", "yaml"]) == 2
    assert "--format yaml needs -o" in capsys.readouterr().err
    assert main(["plan", "--n", "4", "--max-tilt-deg", "200"]) == 2
    assert "--max-tilt-deg: expected a number in [0, 180], got '200'" in capsys.readouterr().err
    assert main(["plan", "--n", "4", "--seed", "-1"]) == 2
    assert "seed must be at least 0" in capsys.readouterr().err
    assert main(["plan", "--n", "9", "--joint-range", "joint9:0:1"]) == 2
    assert "unknown joint 'joint9'; joints: joint1" in capsys.readouterr().err


def test_cli_package_dir_resolves_meshes(capsys, tmp_path):
    from ftkin.cli.plan import load_arm
    from ftkin.kinematics.robots import example_robot_data_share

    share = example_robot_data_share()
    urdf = share / "example-robot-data" / "robots" / "ur_description" / "urdf" / "ur5_robot.urdf"
    # the package (example-robot-data) sits above the URDF: found without --package-dir
    assert main(["plan", "--n", "3", "--urdf", str(urdf), "--sensor-frame", "tool0"]) == 0
    capsys.readouterr()
    # a copy elsewhere: its package:// meshes are found only through --package-dir
    copy = tmp_path / "ur5_robot.urdf"
    copy.write_text(urdf.read_text())
    assert main(["plan", "--n", "3", "--urdf", str(copy), "--sensor-frame", "tool0"]) == 2
    error = capsys.readouterr().err
    assert "give --package-dir DIR" in error and error.count("package://") <= 3  # named once
    args = argparse.Namespace(
        urdf=str(copy), sensor_frame="tool0", tool_frame=None, package_dir=[str(share)]
    )
    arm = load_arm(args)
    assert arm.package_dirs == [str(share)]
    assert arm.geometry("collision").ngeoms > 0


def test_plan_spec_and_the_keyword_shortcut_agree(arm):
    """One plan from a PlanSpec and from flat keywords: the same seed gives the same poses."""
    from ftkin.planning import ExpectedCalibration, PlanSpec, PoseConstraints

    spec = PlanSpec(
        6,
        constraints=PoseConstraints(floor_height=FLOOR, max_tilt=MAX_TILT),
        expected=ExpectedCalibration(tool_weight=10.0, readings_per_pose=2),
        seed=4,
        candidates=300,
    )
    from_spec = plan_poses(arm, spec)
    shortcut = plan_poses(
        arm,
        6,
        floor_height=FLOOR,
        max_tilt=MAX_TILT,
        tool_weight=10.0,
        readings_per_pose=2,
        seed=4,
        candidates=300,
    )
    np.testing.assert_allclose(from_spec.joint_positions, shortcut.joint_positions, atol=1e-12)
    assert from_spec.constraints == spec.constraints
    assert from_spec.evaluation.readings_per_pose == 2
    assert from_spec.evaluation.model.tool_weight == pytest.approx(10.0, rel=1e-12)
    with pytest.raises(InvalidInput, match="plan_poses takes no colour; expected: n, constraints"):
        plan_poses(arm, 6, colour="red")
    with pytest.raises(InvalidInput, match="a PlanSpec or the number of poses with keywords"):
        plan_poses(arm, spec, seed=1)
    with pytest.raises(InvalidInput, match="constraints must be PoseConstraints"):
        PlanSpec(6, constraints={"margin": 0.1})
    with pytest.raises(InvalidInput, match="evaluate_poses takes no margin; expected: tool_weight"):
        evaluate_poses(paper_samples().rotations, margin=0.1)
