"""LiveView: the shared-state protocol, and a real view process drawing a paced control loop."""

from __future__ import annotations

import time
from multiprocessing import shared_memory

import numpy as np
import pytest

from ftkin import SensorNoise
from ftkin.exceptions import InvalidInput
from ftkin.sim.placement import PlacementScenario, admittance_controller
from ftkin.sim.sensor import SimulatedSensor
from ftkin.viz.live_process import StateLayout, read_state

pytest.importorskip("meshcat")

from ftkin.viz import LiveView  # noqa: E402


def test_seqlock_read():
    layout = StateLayout(6)
    state = np.zeros(layout.size)
    state[layout.body] = np.arange(18.0)
    assert read_state(state, layout, 0.0) == (0.0, None)  # nothing new
    state[0] = 3.0  # odd: a write in progress
    assert read_state(state, layout, 2.0)[1] is None
    state[0] = 4.0
    seq, body = read_state(state, layout, 2.0)
    assert seq == 4.0
    np.testing.assert_array_equal(body, np.arange(18.0))
    assert layout.frames == 19 and layout.stop == 20 and layout.size == 21


def test_bad_arguments(arm):
    with pytest.raises(InvalidInput, match="ftkin Arm"):
        LiveView("not an arm")
    with pytest.raises(InvalidInput, match="ControlFrame"):
        LiveView(arm, control_frame="tool")
    # checked before the shared block and the view process are made
    with pytest.raises(InvalidInput, match="force_scale"):
        LiveView(arm, force_scale=0.0)


def test_a_paced_control_loop_is_drawn_at_20_fps_and_the_view_gets_the_latest_state(arm, truth):
    controller = admittance_controller(PlacementScenario(), arm, truth)
    q = np.array([0.0, 0.3, 1.2, 0.0, 1.2, 0.0])
    rng = np.random.default_rng(4)
    raws = SimulatedSensor(truth, SensorNoise.paper()).read(
        np.repeat(arm.rotation_sensor_to_base(q)[None], 2000, axis=0), rng
    )
    raws[:, 2] += 0.5  # N along the sensor z: the arm moves
    with LiveView.for_controller(controller, fps=30.0) as view:
        name, process = view._block.name, view._process
        loop = view.wrap(controller)
        assert loop.frame is controller.frame  # other attributes pass through
        dt, ticks = 1e-3, 0
        frames_before, start = view.frames_drawn, time.perf_counter()
        while time.perf_counter() - start < 1.5:
            q_tick = q
            dq = loop.step(q_tick, raws[ticks % len(raws)], dt)
            q = q_tick + dq * dt
            ticks += 1
            time.sleep(max(ticks * dt - (time.perf_counter() - start), 0.0))
        elapsed = time.perf_counter() - start
        fps = (view.frames_drawn - frames_before) / elapsed
        latest = controller.last_wrench_and_twist  # what the last tick published
        status = controller.last_status
        time.sleep(3.0 / view.fps)  # a couple of sampler periods
        shared = view._state[view.layout.body].copy()
        print(f"{ticks} ticks in {elapsed:.2f} s, the view drew {fps:.1f} frames/s")
        assert fps >= 20.0
        assert view._latest[0] is q_tick  # references, not copies
        assert view._latest[1] is latest[0] and view._latest[2] is latest[1]
        expected = np.concatenate([q_tick, status.contact_wrench, status.twist])
        np.testing.assert_allclose(shared, expected, rtol=1e-15)
        assert view.alive
    assert process.poll() is not None  # the view process has stopped
    with pytest.raises(FileNotFoundError):
        shared_memory.SharedMemory(name=name)


def test_on_tick_sees_every_admittance_tick_and_changes_nothing(arm):
    from ftkin.sim.placement import simulate_placement

    scenario = PlacementScenario(duration=0.05)
    seen = []
    hooked = simulate_placement(
        scenario, arm, on_tick=lambda q, w, t: seen.append((q.copy(), w.copy(), t.copy()))
    )
    plain = simulate_placement(scenario, arm)
    assert len(seen) == round(scenario.duration / scenario.dt)
    np.testing.assert_allclose(hooked.rows(), plain.rows(), rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(
        [w[2] for _, w, _ in seen], plain.measured_force, rtol=1e-12, atol=1e-12
    )  # the controller's F'z per tick


def test_simulate_placement_view(capsys):
    from ftkin.cli import main

    assert main(["simulate", "placement", "--view", "--duration", "0.3"]) == 0
    out = capsys.readouterr().out
    assert "live view: http://" in out
    frames = int(out.split("drew ")[1].split(" frames")[0])
    assert frames >= 1
    assert main(["simulate", "placement", "--view", "--mode", "position"]) == 2
    assert "--view draws one run" in capsys.readouterr().err
