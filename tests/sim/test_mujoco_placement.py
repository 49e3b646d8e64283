"""The placement experiment in MuJoCo: position vs admittance with/without compensation, book and
sponge.
"""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("mujoco")

from ftkin.sim.mujoco.mujoco_placement import simulate_placement_mujoco  # noqa: E402
from ftkin.sim.placement import PlacementScenario, simulate_placement  # noqa: E402
from ftkin.sim.surfaces import BOOK, SPONGE  # noqa: E402

DT = 2e-3  # 500 Hz keeps the test short; the benchmark runs 1 kHz


@pytest.fixture(scope="module", params=[BOOK, SPONGE], ids=["book", "sponge"])
def runs(request):
    surface = request.param
    base = PlacementScenario(surface=surface, dt=DT, duration=4.5 if surface is SPONGE else 2.5)
    out = {}
    for mode, duration in (
        ("position", 1.2),
        ("admittance", base.duration),
        ("admittance-uncompensated", 2.0),
    ):
        out[mode] = simulate_placement_mujoco(
            PlacementScenario(surface=surface, mode=mode, dt=DT, duration=duration)
        )
    return surface, out


def test_admittance_with_compensation_is_gentle_and_settles(runs):
    surface, out = runs
    position, _ = out["position"]
    placed, full = out["admittance"]
    assert placed.peak_contact_force <= 0.3 * position.peak_contact_force
    assert placed.placed and abs(placed.final_force) < 0.05
    speeds = np.abs(full.table[-50:, full.columns.index("dq1") : full.columns.index("dq6") + 1])
    assert speeds.max() < 1e-3  # the arm has stopped [rad/s]
    assert np.isinf(full.first_hold)  # no fault, no oscillation


def test_without_compensation_it_presses_deeper(runs):
    surface, out = runs
    placed, _ = out["admittance"]
    pressed, _ = out["admittance-uncompensated"]
    assert pressed.penetration[-1] > 2.0 * placed.penetration[-1]
    if surface is BOOK:  # settled (the sponge takes longer than this short run)
        # it hands the tool's weight and the bias to the surface too: N ≈ W + tool weight + F0z (≈
        # 2.2 + 3.15 + 0.2 N)
        assert pressed.normal_force[-1] == pytest.approx(2.214 + 3.15 + 0.2, abs=0.1)


def test_mujoco_agrees_with_the_simple_engine(runs):
    """Two independent contact models (a spring-loaded pad in a physics engine, a spring-damper
    formula).
    """
    surface, out = runs
    placed, _ = out["admittance"]
    simple = simulate_placement(
        PlacementScenario(
            surface=surface, mode="admittance", dt=DT, duration=placed.scenario.duration
        )
    )
    assert placed.peak_contact_force == pytest.approx(simple.peak_contact_force, rel=0.05)
    assert placed.penetration[-1] == pytest.approx(simple.penetration[-1], rel=0.05)


def test_the_record_has_joint_states_and_the_ideal_wrench(runs):
    _, out = runs
    run, full = out["position"]
    assert full.columns[:7] == run.COLUMNS
    for name in ("q1", "dq6", "cmd3", "ideal_fz", "ideal_mz", "held"):
        assert name in full.columns
    # in the air at rest the ideal load is the tool plus the object: 3.15 N + 2.214 N along the
    # sensor z (down)
    assert full.column("ideal_fz")[0] == pytest.approx(3.15 + 2.214, abs=0.05)


def test_cli_runs_all_modes_in_mujoco(tmp_path, capsys):
    from ftkin.cli import main
    from ftkin.io.csv_table import read_table

    csv_path, png_path = tmp_path / "all.csv", tmp_path / "all.png"
    assert (
        main(
            [
                "simulate",
                "placement",
                "--engine",
                "mujoco",
                "--mode",
                "all",
                "--surface",
                "book",
                "--duration",
                "0.3",
                "--dt",
                "0.002",
                "-o",
                str(csv_path),
                "--plot",
                str(png_path),
            ]
        )
        == 0
    )
    out = capsys.readouterr().out
    assert out.count("(mujoco)") == 3 and "admittance-uncompensated" in out
    assert ": none" not in out  # no event line without an event
    table = read_table(csv_path)
    assert table.header[:8] == [
        "mode",
        "t",
        "displacement",
        "velocity",
        "force",
        "measured_force",
        "penetration",
        "normal_force",
    ]
    assert "ideal_fz" in table.header and "q6" in table.header
    modes = table.floats(["mode"])[:, 0]
    assert sorted(set(modes)) == [0.0, 1.0, 2.0] and len(modes) == 3 * 150
    assert png_path.read_bytes()[:4] == b"\x89PNG"
