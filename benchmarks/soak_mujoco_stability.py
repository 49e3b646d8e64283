"""Soak of the oscillation detector in MuJoCo: no false trip below the K1 bound, a trip above it.

Below: ``--seconds`` (default 60) of simulated placement cycles per surface at
1 kHz, the admittance with compensation at ``k13 = 0.9 x`` the book's bound
:func:`~ftkin.control.stability.max_stable_k1` (k23 1 mm/(s·N), 5 Hz filter,
one-tick delay); each 7.5 s cycle starts the object 1-4 mm above a fresh
surface (book and sponge) with new sensor noise. Fails (exit 1) on any hold
(oscillation, sensor fault, safety stop) or a cycle that does not place the
object (|F'z| < 0.05 N and the arm stopped at the end of the cycle).

Above: one run at 1.5 x the bound at 1 kHz and one at 1.1 x at 500 Hz on
the book; reports the time from the first contact to the hold (must be < 0.5 s;
a hold before any contact, the payload-inertia loop oscillating in the air,
counts as held too).

Run: ``.venv/bin/python benchmarks/soak_mujoco_stability.py`` (``--seconds 60``).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from ftkin import Arm
from ftkin.control.stability import max_stable_k1
from ftkin.sim.mujoco.placement import placement_scene, simulate_placement_mujoco
from ftkin.sim.placement import PlacementScenario
from ftkin.sim.surfaces import BOOK, SPONGE

CYCLE = 7.5
"""Simulated seconds per placement cycle."""


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--seconds", type=float, default=60.0, help="simulated seconds of cycles per surface"
    )
    args = parser.parse_args()
    arm = Arm.default()
    bound = max_stable_k1(BOOK.stiffness, BOOK.damping, 1e-3, 5.0, k2=1e-3, delay_ticks=1)
    k1 = 0.9 * bound
    rng = np.random.default_rng(0)
    failures = 0
    print(
        f"below: k13 = 0.9 x {bound * 1e3:.3f} mm/N = {k1 * 1e3:.3f} mm/N, 1 kHz, {CYCLE:g} s "
        "cycles"
    )
    print(
        f"{'surface':<8}{'cycles':>7}{'simulated [s]':>15}{'held':>6}{'placed':>8}"
        f"{'max settle [s]':>16}{'wall [s]':>10}"
    )
    for surface in (BOOK, SPONGE):
        cycles = int(np.ceil(args.seconds / CYCLE))
        held = placed = 0
        settle = []
        start = time.perf_counter()
        for cycle in range(cycles):
            scenario = PlacementScenario(
                surface=surface,
                k1=k1,
                duration=CYCLE,
                start_gap=float(rng.uniform(1e-3, 4e-3)),
                seed=cycle,
            )
            run, full = simulate_placement_mujoco(scenario, arm, sim=placement_scene(scenario, arm))
            held += int(np.isfinite(full.first_hold) or run.safety_stop)
            placed += int(run.placed)
            settle.append(run.settle_time)
        wall = time.perf_counter() - start
        failures += held + (cycles - placed)
        print(
            f"{surface.name:<8}{cycles:>7}{cycles * CYCLE:>15.0f}{held:>6}{placed:>8}"
            f"{max(settle):>16.3f}{wall:>10.1f}"
        )

    print("\nabove the bound, book")
    print(
        f"{'rate':<8}{'k13 / bound':>12}{'k13 [mm/N]':>11}{'contact [s]':>13}{'held [s]':>10}"
        f"{'after contact [s]':>19}"
    )
    for dt, factor in ((1e-3, 1.5), (2e-3, 1.1)):
        rate_bound = max_stable_k1(BOOK.stiffness, BOOK.damping, dt, 5.0, k2=1e-3, delay_ticks=1)
        scenario = PlacementScenario(surface=BOOK, k1=factor * rate_bound, dt=dt, duration=2.0)
        run, full = simulate_placement_mujoco(scenario, arm)
        touched = run.normal_force > 0.05
        contact = float(run.time[np.argmax(touched)]) if touched.any() else np.inf
        after = full.first_hold - contact
        failures += int(not (after < 0.5 or full.first_hold < contact))
        print(
            f"{1 / dt:>5.0f} "
            f"Hz{factor:>12.1f}{scenario.k1 * 1e3:>11.3f}{contact:>13.3f}{full.first_hold:>10.3f}"
            f"{after:>19.3f}"
        )
    print("PASS" if failures == 0 else f"FAIL ({failures})")
    return int(failures > 0)


if __name__ == "__main__":
    from _targets import run_benchmark

    raise SystemExit(run_benchmark(main))
