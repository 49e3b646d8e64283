"""The kinds of wrong input, each refused where it arrives with a message naming it (issue 24):
number types, integer ids and magnitudes at the public API.
"""

from __future__ import annotations

import numpy as np
import pytest

import ftkin
from ftkin.calibration.information import SensorNoise
from ftkin.exceptions import InvalidInput, InvalidSamples, UnobservableParameters
from ftkin.sim.sensor import SimulatedSensor
from ftkin.validation import as_in_range, as_integers, as_positive, as_real, as_vector

NOT_REAL = [
    (True, "booleans"),
    (np.bool_(False), "booleans"),
    ([1.0, True, 2.0], "booleans"),
    (1 + 2j, "complex"),
    (np.array([1.0, 2.0, 3.0], dtype=complex), "complex"),
    (np.array([1.0, 2.0, 3.0], dtype=object), "objects"),
    ([1.0, None, 2.0], "objects"),
    ("1.5", "text"),
    (["1", "2", "3"], "text"),
]


@pytest.mark.parametrize("value, kind", NOT_REAL)
def test_scalars_refuse_what_is_not_a_real_number(value, kind):
    for convert in (as_real, lambda v, n: as_positive(v, n), lambda v, n: as_in_range(v, n, 0, 2)):
        with pytest.raises(InvalidInput, match="mass must be .*(numeric|number)"):
            convert(value, "mass")


@pytest.mark.parametrize("value, kind", NOT_REAL)
def test_vectors_refuse_what_is_not_real(value, kind):
    with pytest.raises(InvalidInput, match=f"offset must be .*{kind}|offset must have shape"):
        as_vector(value, 3, "offset")


def test_public_api_refuses_complex_and_booleans(arm):
    with pytest.raises(InvalidInput, match="complex"):
        ftkin.SensorModel.from_tool(0.3, np.array([0, 0, 0.05]) + 0j, [0, 0, 0], [0, 0, 0])
    with pytest.raises(InvalidInput, match="booleans"):
        arm.rotation_sensor_to_base([True] * arm.nq)


@pytest.mark.parametrize(
    "ids, pattern",
    [
        (np.array([0, 2**62, 1], dtype=np.int64), "magnitude at most 2\\*\\*53"),
        ([0.0, 1e19, 1.0], "magnitude at most 2\\*\\*53"),  # wrapped around in astype before
        (np.array([0, 2**64 - 1, 1], dtype=np.uint64), "magnitude at most 2\\*\\*53"),
        ([0.0, np.nan, 1.0], "magnitude at most"),
        ([0.0, 0.5, 1.0], "must be integers"),
        ([0, True, 1], "booleans"),
    ],
)
def test_pose_ids_are_range_checked_before_the_cast(rotations, ids, pattern):
    with pytest.raises(InvalidSamples, match=pattern):
        ftkin.Samples(np.zeros((3, 6)), rotations[:3], pose_ids=ids)
    with pytest.raises(InvalidInput, match=pattern):
        as_integers(ids, "pose ids")


@pytest.mark.parametrize("scale", [1e7, 1e200])
def test_absurd_readings_are_refused_before_the_fit(arm, truth, rng, scale):
    samples = SimulatedSensor(truth, SensorNoise.paper()).samples_at_configurations(
        arm, arm.random_configurations(8, rng, margin=0.3), rng
    )
    with pytest.raises(InvalidSamples, match="beyond ±1e\\+06: expected N and N·m") as info:
        ftkin.calibrate(ftkin.Samples(samples.wrenches * scale, samples.rotations))
    assert not isinstance(info.value, UnobservableParameters)


def test_tick_counts_refuse_booleans_and_absurd_delays():
    from ftkin.control.sensor_faults import SensorLimits
    from ftkin.control.stability import MAX_DELAY_TICKS, max_stable_k1

    with pytest.raises(InvalidInput, match="recovery_ticks"):
        SensorLimits(recovery_ticks=True)
    for delay in (True, MAX_DELAY_TICKS + 1, 10**12):
        with pytest.raises(InvalidInput, match="delay_ticks"):
            max_stable_k1(1e4, 50.0, 1e-3, 30.0, delay_ticks=delay)
