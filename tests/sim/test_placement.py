"""The simulated placement experiment reproduces the paper's findings (METHOD.md §6)."""

from __future__ import annotations

import sys
from dataclasses import replace

import numpy as np
import pinocchio as pin
import pytest

from ftkin.calibration.information import SensorNoise
from ftkin.cli import main
from ftkin.exceptions import InvalidInput, MissingDependency
from ftkin.io.csv_table import read_table
from ftkin.sim.placement import Q_DOWN, PlacementRun, PlacementScenario, simulate_placement, sweep
from ftkin.sim.sensor import paper_like_truth
from ftkin.sim.surfaces import BOOK, SPONGE, Surface, held_object_wrench, surface_by_name

FAST = PlacementScenario(dt=2e-3, k2=2e-3)
"""Coarser tick and a larger k23 than the default so each run takes a fraction of a second."""


@pytest.fixture(scope="module")
def runs(arm) -> dict[tuple[str, str], PlacementRun]:
    out = {}
    for surface in (SPONGE, BOOK):
        out[surface.name, "position"] = simulate_placement(
            replace(FAST, surface=surface, mode="position", duration=1.0), arm
        )
        out[surface.name, "admittance"] = simulate_placement(
            replace(FAST, surface=surface, duration=3.0), arm
        )
    out["sponge", "admittance-uncompensated"] = simulate_placement(
        replace(FAST, mode="admittance-uncompensated", duration=3.0), arm
    )
    return out


def test_position_control_presses_harder_on_the_book(runs):
    sponge, book = runs["sponge", "position"], runs["book", "position"]
    assert book.peak_contact_force > 3 * sponge.peak_contact_force
    assert (
        sponge.final_force < 0 and book.final_force < sponge.final_force
    )  # the paper's sign: pressing is negative
    # It stops at the target, 5 mm into the surface, whatever the force: N = k δ.
    for run, surface in ((sponge, SPONGE), (book, BOOK)):
        assert run.penetration[-1] == pytest.approx(FAST.target_depth, abs=1e-6)
        assert run.normal_force[-1] == pytest.approx(
            surface.stiffness * FAST.target_depth, rel=1e-4
        )
        assert not run.placed


@pytest.mark.parametrize("surface", ["sponge", "book"])
def test_admittance_with_compensation_places_the_object_gently(runs, surface):
    run, position = runs[surface, "admittance"], runs[surface, "position"]
    assert run.placed
    assert abs(run.final_force) < 0.05
    assert abs(run.mean_speed()[-1]) < 1e-4
    # The surface ends carrying the object's weight, and never much more.
    assert run.normal_force[-1] == pytest.approx(FAST.object_weight, abs=0.05)
    assert run.peak_contact_force < 1.1 * FAST.object_weight
    assert run.peak_contact_force < 0.25 * position.peak_contact_force
    assert not run.safety_stop


def test_without_compensation_the_arm_pushes_further_down(runs):
    compensated, raw = runs["sponge", "admittance"], runs["sponge", "admittance-uncompensated"]
    assert raw.penetration[-1] > 2 * compensated.penetration[-1]
    assert not raw.placed
    # It settles where the raw z reading is zero: the true F'z is minus the bias + tool weight along
    # z.
    unloaded_z = paper_like_truth().predict(np.eye(3) @ _sensor_rotation())[2]
    assert raw.final_force == pytest.approx(-unloaded_z, abs=0.05)


def _sensor_rotation():
    from ftkin import Arm

    return Arm.default().rotation_sensor_to_base(np.array(Q_DOWN))


def test_larger_k23_settles_faster(arm):
    runs = sweep(replace(FAST, duration=5.0), "k2", [1e-3, 2e-3, 4e-3], arm)
    times = [run.settle_time for run in runs]
    assert all(np.isfinite(times))
    assert times[0] > times[1] > times[2]


def test_position_form_lowers_the_tool_by_k1_times_the_weight(arm):
    """k23 = 0, far from the surface: the tool moves by ΔX = K1·ΔF once the weight is taken.

    (k1 small enough that the start stays below the 0.05 m/s velocity saturation.)
    """
    k1 = 5e-4
    run = simulate_placement(replace(FAST, k1=k1, k2=0.0, start_gap=0.05, duration=1.5), arm)
    expected = -k1 * (FAST.object_weight - FAST.force_deadband)
    assert run.displacement[-1] == pytest.approx(expected, rel=0.02)
    assert run.peak_contact_force == 0.0


def test_larger_k13_reaches_the_surface_sooner(arm):
    runs = sweep(replace(FAST, duration=1.0), "k1", [0.0, 1e-4, 5e-4], arm)
    first_contact = [run.time[np.argmax(run.normal_force > 0)] for run in runs]
    assert first_contact[0] > first_contact[1] > first_contact[2]


def test_the_controller_sees_the_simulated_sensor(arm):
    quiet = replace(FAST, noise=SensorNoise(1e-12, 1e-12), duration=0.1)
    compensated = simulate_placement(quiet, arm)
    np.testing.assert_allclose(compensated.measured_force, compensated.force, atol=1e-9)
    raw = simulate_placement(replace(quiet, mode="admittance-uncompensated"), arm)
    unloaded_z = paper_like_truth().predict(_sensor_rotation())[2]
    assert raw.measured_force[0] - raw.force[0] == pytest.approx(unloaded_z, abs=1e-9)


def test_scenario_and_surface_validation():
    with pytest.raises(InvalidInput, match="mode"):
        PlacementScenario(mode="force")
    with pytest.raises(InvalidInput, match="gains"):
        PlacementScenario(k1=-1.0)
    with pytest.raises(InvalidInput, match="stiffness"):
        Surface("jelly", stiffness=0.0, damping=1.0)
    with pytest.raises(InvalidInput, match="sponge"):
        surface_by_name("carpet")
    with pytest.raises(InvalidInput, match="gain"):
        sweep(FAST, "k3", [1.0])
    # regression: numpy/TypeError leaked for non-numbers, inf duration overflowed
    with pytest.raises(InvalidInput, match="gains"):
        PlacementScenario(k1="0.1")
    with pytest.raises(InvalidInput, match="dt"):
        PlacementScenario(dt=None)
    with pytest.raises(InvalidInput, match="duration"):
        PlacementScenario(duration=float("inf"))
    with pytest.raises(InvalidInput, match="damping"):
        Surface("jelly", stiffness=1.0, damping="soft")


def test_surface_pushes_but_never_pulls():
    assert SPONGE.normal_force(-0.001, 1.0) == 0.0
    assert SPONGE.normal_force(0.001, -1.0) == 0.0
    assert SPONGE.normal_force(0.001, 0.01) == pytest.approx(2.0e3 * 0.001 + 20.0 * 0.01)


# --------------------------------------------------------------------- CLI
def test_cli_writes_the_time_series_and_a_plot(tmp_path, capsys):
    csv_path, png_path = tmp_path / "run.csv", tmp_path / "run.png"
    code = main(
        [
            "simulate",
            "placement",
            "--engine",
            "simple",
            "--surface",
            "book",
            "--mode",
            "admittance",
            "--k1",
            "0.1",
            "--k2",
            "2",
            "--duration",
            "0.5",
            "--dt",
            "0.002",
            "-o",
            str(csv_path),
            "--plot",
            str(png_path),
        ]
    )
    assert code == 0
    assert "peak contact force" in capsys.readouterr().out
    table = read_table(csv_path)
    assert table.header == list(PlacementRun.COLUMNS)
    values = table.floats(table.header)
    expected = simulate_placement(
        replace(FAST, surface=BOOK, k1=1e-4, k2=2e-3, duration=0.5)
    ).rows()
    np.testing.assert_allclose(values, expected, rtol=1e-12, atol=1e-15)
    assert png_path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_cli_sweep_adds_a_gain_column(tmp_path):
    csv_path = tmp_path / "sweep.csv"
    assert (
        main(
            [
                "simulate",
                "placement",
                "--engine",
                "simple",
                "--sweep",
                "k2",
                "--values",
                "1,2",
                "--duration",
                "0.2",
                "--dt",
                "0.002",
                "-o",
                str(csv_path),
            ]
        )
        == 0
    )
    table = read_table(csv_path)
    gains = table.floats(["gain"])[:, 0]
    assert table.header[0] == "gain" and sorted(set(gains)) == [1.0, 2.0] and len(gains) == 200


def test_cli_sweep_needs_values(capsys):
    assert main(["simulate", "placement", "--sweep", "k1"]) == 2
    assert "--values" in capsys.readouterr().err


def test_plots_without_matplotlib_raise_missing_dependency(monkeypatch, tmp_path, runs):
    from ftkin.sim.placement_plots import plot_runs

    monkeypatch.setitem(sys.modules, "matplotlib", None)
    with pytest.raises(MissingDependency, match="plots"):
        plot_runs([runs["sponge", "position"]], tmp_path / "x.png")


def test_held_object_wrench_matches_np_cross(rng):
    rotation, origin, tool = pin.exp3(rng.normal(size=3)), rng.normal(size=3), rng.normal(size=3)
    height, weight, normal = 0.04, 2.214, 1.3  # m, N, N
    axis = rotation[:, 2]
    moment = np.cross(tool + axis * height - origin, [0, 0, normal]) + np.cross(
        tool + axis * height / 2 - origin, [0, 0, -weight]
    )
    expected = np.concatenate([rotation.T @ [0, 0, normal - weight], rotation.T @ moment])
    np.testing.assert_allclose(
        held_object_wrench(rotation, origin, tool, height, weight, normal), expected, atol=1e-14
    )
