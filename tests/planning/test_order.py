"""The vectorised 2-opt gives the tours of the plain double loop."""

from __future__ import annotations

from ftkin.planning.order import _two_opt, joint_distances, nearest_neighbour


def _plain_two_opt(distances, order):
    order = list(order)
    count = len(order)
    improved = True
    while improved:
        improved = False
        for i in range(count - 1):
            for j in range(i + 1, count):
                before = distances[order[i - 1], order[i]] if i > 0 else 0.0
                after = distances[order[j], order[j + 1]] if j < count - 1 else 0.0
                new_before = distances[order[i - 1], order[j]] if i > 0 else 0.0
                new_after = distances[order[i], order[j + 1]] if j < count - 1 else 0.0
                if new_before + new_after < before + after - 1e-12:
                    order[i : j + 1] = order[i : j + 1][::-1]
                    improved = True
    return order


def test_two_opt_matches_the_double_loop(rng):
    for count in (3, 5, 12, 25, 40):
        distances = joint_distances(rng.uniform(-3.0, 3.0, size=(count, 6)))
        for start in range(0, count, max(1, count // 5)):
            tour = nearest_neighbour(distances, start)
            assert _two_opt(distances, tour) == _plain_two_opt(distances, tour)
        shuffled = list(rng.permutation(count))
        assert _two_opt(distances, shuffled) == _plain_two_opt(distances, shuffled)


def test_revolute_mask_leaves_a_last_prismatic_joint_alone():
    # Pinocchio's universe joint (joints[0]) reports JointModelRX with idx_q -1: counting it
    # marked the last coordinate revolute, and unwinding moved a prismatic joint by 2π m.
    import numpy as np
    import pinocchio as pin

    from ftkin.planning.order import revolute_mask, unwind_revolute

    model = pin.Model()
    joint = model.addJoint(0, pin.JointModelRZ(), pin.SE3.Identity(), "spin")
    model.addJoint(joint, pin.JointModelPZ(), pin.SE3.Identity(), "slide")
    mask = revolute_mask(model)
    np.testing.assert_array_equal(mask, [True, False])  # booleans: exact by nature
    q = unwind_revolute([0.5, 4.0], [-7.0, -10.0], [7.0, 10.0], mask)
    np.testing.assert_allclose(q, [0.5, 4.0], rtol=1e-12)
