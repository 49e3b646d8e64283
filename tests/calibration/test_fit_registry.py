"""``ftkin.calibrate`` picks its fit from the samples' type (:mod:`ftkin.calibration.fit_registry`).

The table names each samples type by its module and name (so it imports none of them): every
entry must name a real class and load the fit its docs name; a subclass is fitted as its base;
anything else is refused with the types it could have been. The static expectation is the
simulated truth (noise-free readings from a known tool), not a fit read back.
"""

from __future__ import annotations

import importlib

import numpy as np
import pytest

import ftkin
from ftkin.calibration import fit_registry
from ftkin.calibration.estimate import calibrate_static
from ftkin.calibration.fused_fit import calibrate_fused
from ftkin.calibration.imu_fit import calibrate_imu
from ftkin.exceptions import InvalidInput

EXPECTED = {
    "ftkin.calibration.samples.Samples": calibrate_static,
    "ftkin.calibration.imu_samples.ImuSamples": calibrate_imu,
    "ftkin.calibration.fused_samples.FusedSamples": calibrate_fused,
}


def test_every_entry_names_a_samples_class_and_loads_its_fit():
    assert set(fit_registry.FITS) == set(EXPECTED)
    for name, load in fit_registry.FITS.items():
        module, _, qualified = name.rpartition(".")
        kind = getattr(importlib.import_module(module), qualified)
        assert isinstance(kind, type) and f"{kind.__module__}.{kind.__qualname__}" == name
        assert load() is EXPECTED[name]


def test_ftkin_calibrate_is_the_registry():
    assert ftkin.calibrate is fit_registry.calibrate
    assert ftkin.calibration.calibrate is fit_registry.calibrate


class _MySamples(ftkin.Samples):
    """A user's subclass: fitted as its nearest registered base, ``Samples``."""


def test_a_subclass_is_fitted_by_its_base_fit(tool, rotations):
    samples = _MySamples.from_rotations(rotations, tool.predict(rotations))
    assert type(samples) is _MySamples
    assert fit_registry.fit_for(samples) is calibrate_static
    result = ftkin.calibrate(samples, method="linear")
    # noise-free readings: the truth back to rounding
    np.testing.assert_allclose(result.to_vector(), tool.to_vector(), rtol=0, atol=1e-9)


@pytest.mark.parametrize("given", [None, [[0.0] * 6], "samples.csv", np.zeros((3, 6))])
def test_anything_else_is_refused_with_the_types_it_could_be(given):
    expected = rf"must be an ftkin\.Samples, got {type(given).__name__}: .*ImuSamples.*FusedSamples"
    with pytest.raises(InvalidInput, match=expected):
        ftkin.calibrate(given)
