"""The clearance of the self-collision check, on both sides of it.

The check asks coal for collisions with a security margin; the expectation is the smallest
distance between the checked pairs computed apart (``pin.computeDistances`` on the same hulls):
a clearance 0.1 mm below it passes the configuration, 0.1 mm above it refuses it.
"""

import numpy as np
import pinocchio as pin
import pytest

from ftkin.exceptions import InvalidInput
from ftkin.kinematics.collision import DEFAULT_CLEARANCE, SelfCollision
from ftkin.kinematics.fr3 import fr3_arm


@pytest.fixture(scope="module")
def fr3():
    return fr3_arm()


def nearest_pair(check: SelfCollision, q) -> float:
    """Smallest distance [m] between the checked pairs at ``q``, by distance queries."""
    data = pin.GeometryData(check.geometry_model)
    pin.computeDistances(check.model, check.model.createData(), check.geometry_model, data, q)
    return min(result.min_distance for result in data.distanceResults)


@pytest.mark.parametrize("seed", range(3))
def test_the_clearance_from_both_sides(fr3, seed):
    rng = np.random.default_rng(seed)
    probe = SelfCollision(fr3, clearance=0.0)
    # below every pair's distance at home (link 5 to link 7: 0.022 m), where no pair's clearance
    # is capped by it
    nearest = 0.02  # [m]
    q = next(
        q
        for q in fr3.random_configurations(400, rng, 0.05)
        if 0.003 < nearest_pair(probe, q) < nearest
    )
    distance = nearest_pair(probe, q)
    assert not SelfCollision(fr3, clearance=distance - 1e-4).in_collision(q)
    assert SelfCollision(fr3, clearance=distance + 1e-4).in_collision(q)


def test_pairs_keep_the_clearance_or_their_home_distance(fr3):
    check = SelfCollision(fr3, clearance=0.3)
    home = pin.GeometryData(check.geometry_model)
    pin.computeDistances(
        check.model,
        check.model.createData(),
        check.geometry_model,
        home,
        check.reference_configuration,
    )
    at_home = np.array([result.min_distance for result in home.distanceResults])
    np.testing.assert_allclose(check.pair_clearances, np.minimum(0.3, at_home), atol=1e-9)
    assert SelfCollision(fr3).clearance == DEFAULT_CLEARANCE == 0.02


@pytest.mark.parametrize("value", [-0.01, float("nan"), "far", 2.0])
def test_a_clearance_that_is_not_a_distance_is_refused(fr3, value):
    with pytest.raises(InvalidInput, match="clearance"):
        SelfCollision(fr3, clearance=value)
