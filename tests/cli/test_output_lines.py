"""Output lines carry information, and labels say what actually ran."""

from __future__ import annotations

import pytest

from ftkin.cli import main


def test_view_labels_the_simple_engine_it_runs(monkeypatch, capsys):
    import ftkin.cli.simulate as simulate
    from ftkin.sim.placement import simulate_placement

    monkeypatch.setattr(simulate, "_run_viewed", simulate_placement)  # no browser in a test
    args = ["simulate", "placement", "--mode", "admittance", "--duration", "0.05", "--view"]
    assert main([*args, "--engine", "mujoco"]) == 0
    out = capsys.readouterr().out
    assert "(simple)" in out and "(mujoco)" not in out


def test_mujoco_run_prints_no_empty_event(capsys):
    pytest.importorskip("mujoco")
    args = ["simulate", "placement", "--engine", "mujoco", "--mode", "admittance"]
    assert main([*args, "--duration", "0.05", "--dt", "0.002"]) == 0
    assert ": none" not in capsys.readouterr().out
