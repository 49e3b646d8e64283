"""Every unit pair a Net F/T box can be set to, to SI: the factors, and through the real pynetft.

The expected values are computed here from the definitions (NIST SP 811: 1 lb = 0.45359237 kg,
g_n = 9.80665 m/s², 1 in = 0.0254 m, 1 ft = 12 in) in exact rational arithmetic, and from the
counts the emulated box encodes: never from ftkin's own tables.
"""

from __future__ import annotations

import itertools
from fractions import Fraction

import numpy as np
import pytest

from ftkin.exceptions import InvalidInput
from ftkin.sensors.units import TORQUE_UNITS, newton_metres_per, newtons_per, wrench_scale

pynetft = pytest.importorskip("pynetft", reason="pynetft is not installed (extra 'ati')")

from ftkin.sensors import AtiNetFT  # noqa: E402

POUND = Fraction("0.45359237")  # [kg]
G_N = Fraction("9.80665")  # [m/s²]
INCH = Fraction("0.0254")  # [m]
FOOT = 12 * INCH

NEWTONS = {  # the box's force units (pynetft's ForceUnit values) → N, and how the box names them
    "N": (Fraction(1), "N"),
    "kN": (Fraction(1000), "kN"),
    "lbf": (POUND * G_N, "lbf"),
    "klbf": (1000 * POUND * G_N, "klbf"),
    "kgf": (G_N, "kgf"),
}
NEWTON_METRES = {  # torque units → N·m, and the name the box serves in netftapi2.xml
    "N-m": (Fraction(1), "Nm"),
    "N-mm": (Fraction(1, 1000), "Nmm"),
    "kN-m": (Fraction(1000), "kN-m"),
    "lbf-in": (POUND * G_N * INCH, "lbf-in"),
    "lbf-ft": (POUND * G_N * FOOT, "lbf-ft"),
    "kgf-cm": (G_N / 100, "kgf-cm"),
}
COUNTS = [1_234_567, -2_345_678, 345_679, -456_789, 567_891, -678_912]
COUNTS_PER_FORCE = 1_000_000
COUNTS_PER_TORQUE = 1_000  # a box in N-mm needs about 1000 counts per unit to fit int32


def test_every_pynetft_unit_has_an_exact_factor():
    assert {unit.value for unit in pynetft.ForceUnit} - {"unknown"} == set(NEWTONS)
    assert {unit.value for unit in pynetft.TorqueUnit} - {"unknown"} == set(NEWTON_METRES)
    for unit in pynetft.ForceUnit:
        if unit.value != "unknown":
            np.testing.assert_allclose(newtons_per(unit), float(NEWTONS[unit.value][0]), rtol=1e-15)
    for unit in pynetft.TorqueUnit:
        if unit.value != "unknown":
            np.testing.assert_allclose(
                newton_metres_per(unit), float(NEWTON_METRES[unit.value][0]), rtol=1e-15
            )


@pytest.mark.parametrize("unit", ["unknown", "gf", "lb", "Nm ", "", "n"])
def test_an_unknown_unit_is_refused_naming_the_known_ones(unit):
    with pytest.raises(InvalidInput, match="N, kN, lbf"):
        newtons_per(unit)
    with pytest.raises(InvalidInput, match="N-m, N-mm"):
        newton_metres_per(unit)
    assert set(TORQUE_UNITS) == set(NEWTON_METRES)


def test_a_unit_that_is_no_name_is_refused():
    with pytest.raises(InvalidInput, match="named by a string, got 3"):
        newtons_per(3)


def test_the_scale_puts_force_then_torque():
    np.testing.assert_allclose(
        wrench_scale("lbf", "N-mm"), [float(POUND * G_N)] * 3 + [1e-3] * 3, rtol=1e-15
    )


def test_every_unit_pair_through_pynetft_gives_the_si_wrench(box, ports):
    """30 pairs: the box serves its units in netftapi2.xml, pynetft scales the counts into them,
    ftkin converts; the SI wrench must match counts / counts-per-unit × the exact factor."""
    box.set(
        counts=COUNTS,
        calibration={"cfgcpf": COUNTS_PER_FORCE, "cfgcpt": COUNTS_PER_TORQUE},
    )
    worst = 0.0
    for force_unit, torque_unit in itertools.product(NEWTONS, NEWTON_METRES):
        (to_newtons, force_name), (to_newton_metres, torque_name) = (
            NEWTONS[force_unit],
            NEWTON_METRES[torque_unit],
        )
        box.set(calibration={"scfgfu": force_name, "scfgtu": torque_name})
        with AtiNetFT(box.host, **ports) as sensor:
            _, wrench = sensor.read()
            configured = sensor.health().sensor_configuration.calibration
        assert (configured.force_unit.value, configured.torque_unit.value) == (
            force_unit,
            torque_unit,
        )
        expected = [float(Fraction(c, COUNTS_PER_FORCE) * to_newtons) for c in COUNTS[:3]] + [
            float(Fraction(c, COUNTS_PER_TORQUE) * to_newton_metres) for c in COUNTS[3:]
        ]
        np.testing.assert_allclose(
            wrench, expected, rtol=1e-9, err_msg=f"{force_unit}, {torque_unit}"
        )
        worst = max(worst, float(np.max(np.abs(wrench / np.array(expected) - 1.0))))
    assert worst < 1e-9
