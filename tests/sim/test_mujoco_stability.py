"""The K1 bound and the oscillation detector, closed-loop in MuJoCo on the book (the stiff
contact).
"""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("mujoco")

from ftkin.control import SensorFault  # noqa: E402
from ftkin.control.stability import max_stable_k1  # noqa: E402
from ftkin.sim.mujoco.mujoco_placement import simulate_placement_mujoco  # noqa: E402
from ftkin.sim.placement import PlacementScenario  # noqa: E402
from ftkin.sim.surfaces import BOOK  # noqa: E402

DT = 1e-3


def _bound(dt=DT, cutoff=5.0, k2=1e-3):
    return max_stable_k1(BOOK.stiffness, BOOK.damping, dt, cutoff, k2=k2, delay_ticks=1)


@pytest.mark.parametrize("dt, factor", [(1e-3, 1.5), (2e-3, 1.1)])
def test_above_the_bound_the_detector_holds_the_arm_within_half_a_second(dt, factor):
    scenario = PlacementScenario(
        surface=BOOK, mode="admittance", k1=factor * _bound(dt), dt=dt, duration=1.3
    )
    run, full = simulate_placement_mujoco(scenario)
    touch = run.time[np.argmax(run.normal_force > 0.05)]
    assert 0.3 < touch < full.first_hold < touch + 0.5
    message = full.events[-1][1]
    assert message.startswith("oscillation") and "lower k1" in message
    after = full.table[run.time >= full.first_hold]
    commands = after[:, full.columns.index("cmd1") : full.columns.index("cmd6") + 1]
    assert np.all(commands == 0.0) and np.all(after[:, -1] == 1.0)  # held to the end (latched)
    assert SensorFault.OSCILLATION.value == "oscillation"


def test_below_the_bound_no_trip_over_repeated_placements():
    k1 = 0.9 * _bound()
    for seed in (1, 2):  # the benchmark soak runs 60 s of such cycles
        run, full = simulate_placement_mujoco(
            PlacementScenario(
                surface=BOOK, mode="admittance", k1=k1, dt=DT, duration=2.0, seed=seed
            )
        )
        assert np.isinf(full.first_hold) and not run.safety_stop
        assert run.normal_force[-1] == pytest.approx(2.214, abs=0.1)  # the object rests on the book
