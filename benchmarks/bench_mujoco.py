"""Closed loop in MuJoCo: speed, the placement table and the K1 stability bound.

1. Speed: simulated seconds per wall second of :func:`ftkin.sim.mujoco.run_closed_loop`
   (admittance on the book, ``JointAdmittance`` in the loop, noisy delayed sensor) at
   1 kHz, 500 Hz and 125 Hz, median of ``--repeats``; beside it the floor measured in
   the same run: the bare physics (``mj_step`` with a zero command for the same
   simulated time) and the controller alone (``JointAdmittance.step`` per tick).
   Target: >= 5x real time at 1 kHz. The loop is also timed in process CPU time:
   on a shared machine the wall clock counts the time other processes hold the cores.
2. Placement (1 kHz, 5 s, the paper's scenario): peak contact force, settle time
   (``|F'z| < 0.05 N`` and stopped), final depth of the pad and final ``F'z``, per
   surface and mode, MuJoCo beside the simple engine.
3. Stability on the book: the linear bound :func:`~ftkin.control.stability.max_stable_k1`
   per rate, and what MuJoCo does at multiples of it (the time the oscillation
   detector holds the arm, after the first contact or in the air).

Run: ``.venv/bin/python benchmarks/bench_mujoco.py`` (``--quick`` for a short run).
"""

from __future__ import annotations

import argparse
import os
import time

import mujoco
import numpy as np

from ftkin import Arm
from ftkin.control.stability import max_stable_k1
from ftkin.sim.mujoco.loop import run_closed_loop
from ftkin.sim.mujoco.placement import placement_scene, simulate_placement_mujoco
from ftkin.sim.mujoco.sensor import MujocoSensor
from ftkin.sim.placement import MODES, PlacementScenario, admittance_controller, simulate_placement
from ftkin.sim.sensor import paper_like_truth
from ftkin.sim.surfaces import BOOK, SPONGE


def speed(arm: Arm, dt: float, seconds: float, repeats: int) -> tuple[float, ...]:
    """Median real-time factors: closed loop (wall clock), (process CPU time), (median tick), bare
    physics, controller alone.

    The median-tick factor is ``dt`` over the median time between successive
    physics steps of the closed loop (one whole tick: sensor, controller,
    recording, physics): a tick is short enough to run mostly uninterrupted, so
    the median shows the cost of a tick without the time other processes hold
    the cores.
    """
    scenario = PlacementScenario(surface=BOOK, dt=dt, duration=seconds)
    sim = placement_scene(scenario, arm)
    truth = paper_like_truth()
    loop, cpu, ticks, physics, control = [], [], [], [], []
    step, stamps = sim.step, []

    def timed_step(dq, duration):
        stamps.append(time.perf_counter())
        step(dq, duration)

    for _ in range(repeats):
        controller = admittance_controller(scenario, arm, sim.tool_sensor_model(bias=truth.bias))
        sensor = MujocoSensor(truth.bias, scenario.noise, seed=0)
        start, start_cpu = time.perf_counter(), time.process_time()
        run_closed_loop(sim, controller, seconds, dt, sensor=sensor)
        loop.append(seconds / (time.perf_counter() - start))
        cpu.append(seconds / (time.process_time() - start_cpu))
        stamps.clear()
        sim.step = timed_step
        run_closed_loop(sim, controller, seconds, dt, sensor=sensor)
        sim.step = step
        ticks.append(dt / float(np.median(np.diff(stamps))))
        sim.reset()
        zero, steps = np.zeros(arm.nq), int(round(seconds / dt))
        start = time.perf_counter()
        for _ in range(steps):
            sim.step(zero, dt)
        physics.append(seconds / (time.perf_counter() - start))
        controller.reset()
        q, raw = sim.q0, sim.ideal_wrench_in_sensor() + truth.bias
        rows = (
            raw + np.random.default_rng(0).standard_normal((steps, 6)) * scenario.noise.channel_std
        )
        start = time.perf_counter()
        for row in rows:
            controller.step(q, row, dt)
        control.append(seconds / (time.perf_counter() - start))
    return tuple(float(np.median(values)) for values in (loop, cpu, ticks, physics, control))


def placement_rows(arm: Arm, duration: float) -> list[tuple]:
    rows = []
    for surface in (BOOK, SPONGE):
        for mode in MODES:
            scenario = PlacementScenario(surface=surface, mode=mode, duration=duration)
            run, full = simulate_placement_mujoco(scenario, arm)
            simple = simulate_placement(scenario, arm)
            rows.append((surface.name, mode, run, simple, full.first_hold))
    return rows


def stability_rows(arm: Arm, factors, duration: float) -> list[tuple]:
    rows = []
    for dt in (1e-3, 2e-3, 8e-3):
        bound = max_stable_k1(BOOK.stiffness, BOOK.damping, dt, 5.0, k2=1e-3, delay_ticks=1)
        for factor in factors:
            scenario = PlacementScenario(surface=BOOK, k1=factor * bound, dt=dt, duration=duration)
            run, full = simulate_placement_mujoco(scenario, arm)
            touched = run.normal_force > 0.05
            touch = float(run.time[np.argmax(touched)]) if touched.any() else np.inf
            rows.append((dt, bound, factor, touch, full.first_hold, run.peak_contact_force))
    return rows


def print_speed(arm: Arm, repeats: int) -> None:
    print("\n1. speed: simulated seconds per wall second (median of", repeats, "runs of 3 s)")
    print(
        f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores (a shared machine slows "
        "every column)"
    )
    print(
        f"{'rate':<8}{'closed loop':>13}{'(CPU time)':>12}{'(median tick)':>15}{'physics only':>14}"
        f"{'controller only':>17}  target"
    )
    for dt in (1e-3, 2e-3, 8e-3):
        loop, cpu, tick, physics, control = speed(arm, dt, 3.0, repeats)
        target = f">= 5x CPU {'PASS' if cpu >= 5 else 'FAIL'}" if dt == 1e-3 else ""
        print(
            f"{1 / dt:>5.0f} "
            f"Hz{loop:>12.1f}x{cpu:>11.1f}x{tick:>14.1f}x{physics:>13.1f}x{control:>16.1f}x  "
            f"{target}"
        )


def print_placement(arm: Arm) -> None:
    print("\n2. placement, 1 kHz, 5 s (MuJoCo | simple engine)")
    print(
        f"{'surface':<8}{'mode':<26}{'peak N [N]':>18}{'settle [s]':>18}{'depth [mm]':>18}"
        f"{'final Fz [N]':>20}{'held':>7}"
    )
    for surface, mode, run, simple, hold in placement_rows(arm, 5.0):
        pair = lambda a, b, f: f"{a:{f}} | {b:{f}}"  # noqa: E731
        print(
            f"{surface:<8}{mode:<26}"
            f"{pair(run.peak_contact_force, simple.peak_contact_force, '7.2f'):>18}"
            f"{pair(run.settle_time, simple.settle_time, '6.3f'):>18}"
            f"{pair(run.penetration[-1] * 1e3, simple.penetration[-1] * 1e3, '6.3f'):>18}"
            f"{pair(run.final_force, simple.final_force, '+7.3f'):>20}"
            f"{'yes' if np.isfinite(hold) else 'no':>7}"
        )


def print_stability(arm: Arm, factors) -> None:
    print(
        "\n3. stability on the book (k23 1 mm/(s·N), 5 Hz filter, one-tick sensor delay), 2 s runs"
    )
    print(
        "bounds [mm/N]: ideal arm | 60 Hz servos with the payload in contact (0.75 kg) | in free "
        "air (0.55 kg)"
    )
    for dt in (1e-3, 2e-3, 8e-3):
        ideal = max_stable_k1(BOOK.stiffness, BOOK.damping, dt, 5.0, k2=1e-3)
        contact = max_stable_k1(
            BOOK.stiffness, BOOK.damping, dt, 5.0, k2=1e-3, servo_bandwidth=60.0, mass=0.75
        )
        air = max_stable_k1(0.0, 0.0, dt, 5.0, k2=1e-3, servo_bandwidth=60.0, mass=0.55)
        print(f"{1 / dt:>5.0f} Hz  {ideal * 1e3:.3f} | {contact * 1e3:.3f} | {air * 1e3:.3f}")
    print(
        f"{'rate':<8}{'bound [mm/N]':>13}{'k13 / bound':>12}{'touch [s]':>11}{'held [s]':>10}  "
        "verdict"
    )
    for dt, bound, factor, touch, hold, _ in stability_rows(arm, factors, 2.0):
        if np.isinf(hold):
            verdict = "no trip"
        elif hold < touch:
            verdict = "held in the air (payload-inertia loop)"
        else:
            verdict = f"held {hold - touch:.3f} s after contact"
        print(
            f"{1 / dt:>5.0f} Hz{bound * 1e3:>13.3f}{factor:>12.1f}{touch:>11.3f}{hold:>10.3f}  "
            f"{verdict}"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--quick",
        action="store_true",
        help="shorter runs (speed 2 s x 3, placement 5 s, fewer stability runs)",
    )
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument(
        "--only", choices=("speed", "placement", "stability"), help="run one section"
    )
    args = parser.parse_args()
    arm = Arm.default()
    repeats = 3 if args.quick else args.repeats
    print(f"mujoco {mujoco.__version__}; bundled arm, MuJoCo timestep 0.5 ms, servos 60 Hz")
    run = lambda section: args.only in (None, section)  # noqa: E731
    if run("speed"):
        print_speed(arm, repeats)
    if run("placement"):
        print_placement(arm)
    if run("stability"):
        print_stability(arm, (0.5, 1.5, 2.0) if args.quick else (0.5, 0.9, 1.1, 1.3, 1.5, 2.0))


if __name__ == "__main__":
    from _targets import run_benchmark

    raise SystemExit(run_benchmark(main))
