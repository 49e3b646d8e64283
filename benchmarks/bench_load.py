"""The load in the hand (issue 39): the paper's Table 4 with the load unknown, in MuJoCo.

Setup: the bundled arm in MuJoCo (``ftkin.sim.mujoco.load_recording``): the gripper body carries a
child body whose mass is Table 4's weight over 9.8 m/s² (its COM 5–9 cm below the sensor, at one of
three places), set per reading; sensor bias [1.2, −0.8, 2.5] N, [0.05, −0.03, 0.02] N·m and white
noise 0.02 N / 0.002 N·m per reading (seeded), 1 kHz. ftkin sees q and the raw readings only: a
``DynamicCompensator`` of the tool (its mass, COM and inertia from MuJoCo's bodies) with a
``LoadTracker`` part (``ftkin.sim.mujoco.load_experiment.run_load_trial``): still 0.3 s, the load
lifted in 10 ms, held still 1.09 s, the wrist turned 60° about joint 5 then joint 4 (1 s each, a
0.3 s dwell after each), turned back, set down in 10 ms.

Rows:

1. Table 4 beside the paper: the true weight, the paper's computed weight and error, ftkin's
   identified weight ``m · 9.8`` 1 s after the grasp (held still) and its error (target ≤ 0.5 %),
   the COM error after the turns (target ≤ 2 mm), the grasp and release delays from the end of the
   mass step (target ≤ 50 ms) and any other event but contacts (target: none);
2. hand guiding (``run_guiding``): the arm moved by segments with five pushes up to 20 N (two
   empty, three carrying the 3.180 N load) and the load set on a surface taking 70 % of its weight;
   target: no grasp, release or tool change but the real ones, every push and the surface reported
   as ``contact``, the mass after them within 0.5 %;
3. cost: ``LoadTracker.tick`` (the per-tick update, a block end every sixth call) against
   ``Compensator.compensate`` (FK and the tool's compensation), alternating blocks, CPU time, the
   median of per-repeat ratios (target ≤ 2×); and the whole ``compensate`` with a load part;
4. the placement (``run_placement``): admittance lowers the 2.214 N object onto the sponge and the
   book while a tracker (gripper closed) identifies it; "placed" when the force along gravity is
   back within ±0.05 N of the empty tool's, beside the truth's settle time (MuJoCo's compensated
   force and the tool's speed); targets: mass ≤ 0.5 %, only grasp and contact, ≤ 0.1 s apart.

Run: ``.venv/bin/python benchmarks/bench_load.py``
"""

from __future__ import annotations

import os
import sys
import time

import numpy as np

from ftkin import Arm, Compensator
from ftkin.calibration.information import SensorNoise
from ftkin.control.load_events import LoadTracker
from ftkin.sim.mujoco.load_experiment import (
    PAPER_G,
    TABLE4_COMPUTED,
    TABLE4_WEIGHTS,
    run_guiding,
    run_load_trial,
    run_placement,
)
from ftkin.sim.mujoco.load_recording import MujocoLoadRecorder
from ftkin.sim.sensor import paper_like_truth
from ftkin.sim.surfaces import BOOK, SPONGE

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from _targets import verdict  # noqa: E402

POSITIONS = [(0.01, -0.008, 0.07), (0.0, 0.012, 0.05), (-0.015, 0.0, 0.09)]


def paired(floor, function, repeats: int = 41, calls: int = 3000):
    """Median seconds per call of ``floor`` and ``function`` and the median ratio (alternating
    blocks, CPU time: as bench_control.py)."""
    for _ in range(calls // 4):
        floor()
        function()
    floors, values, ratios = [], [], []
    for repeat in range(repeats):
        pair = []
        for timed in (floor, function) if repeat % 2 == 0 else (function, floor):
            start = time.process_time()
            for _ in range(calls):
                timed()
            pair.append((time.process_time() - start) / calls)
        floor_time, value = pair if repeat % 2 == 0 else pair[::-1]
        floors.append(floor_time)
        values.append(value)
        ratios.append(value / floor_time)
    return float(np.median(floors)), float(np.median(values)), float(np.median(ratios))


def table4(arm) -> None:
    print("1. Table 4, the load unknown (MuJoCo; g = 9.8 m/s² for the weights)")
    print(
        f"{'true N':>8}{'paper N':>9}{'err %':>7}{'ftkin N':>10}{'err %':>8}{'COM mm':>8}"
        f"{'grasp ms':>10}{'release ms':>12}  other events"
    )
    worst = {"mass": 0.0, "com": 0.0, "delay": 0.0, "other": 0}
    for i, (weight, paper) in enumerate(zip(TABLE4_WEIGHTS, TABLE4_COMPUTED)):
        position = POSITIONS[i % 3]
        trial = run_load_trial(weight, position, seed=i, recorder=MujocoLoadRecorder(position))
        computed = trial.mass_held * PAPER_G
        error = abs(trial.mass_held / trial.true_mass - 1) * 100
        com = float(np.max(np.abs(trial.com - trial.true_com))) * 1e3
        others = [e.kind for e in trial.events if e.kind not in ("grasp", "release", "contact")]
        others += (
            []
            if [e.kind for e in trial.events if e.kind != "contact"]
            == [
                "grasp",
                "release",
            ]
            else ["(grasp/release count)"]
        )
        print(
            f"{weight:>8.3f}{paper:>9.3f}{(paper / weight - 1) * 100:>7.2f}{computed:>10.4f}"
            f"{error:>8.3f}{com:>8.3f}{trial.grasp_delay * 1e3:>10.0f}"
            f"{trial.release_delay * 1e3:>12.0f}  {', '.join(others) or 'none'}"
        )
        worst["mass"] = max(worst["mass"], error)
        worst["com"] = max(worst["com"], com)
        worst["delay"] = max(worst["delay"], trial.grasp_delay, trial.release_delay)
        worst["other"] += len(others)
    print(
        f"   mass within 0.5 % 1 s after the grasp: worst {worst['mass']:.3f} % "
        f"{verdict(worst['mass'] <= 0.5)}"
    )
    print(
        f"   COM within 2 mm after the turns: worst {worst['com']:.3f} mm "
        f"{verdict(worst['com'] <= 2.0)}"
    )
    print(
        f"   grasp and release within 50 ms: worst {worst['delay'] * 1e3:.0f} ms "
        f"{verdict(worst['delay'] <= 0.05)}"
    )
    print(
        f"   events other than grasp, release, contact: {worst['other']} "
        f"{verdict(worst['other'] == 0)}"
    )


def guiding(arm) -> None:
    print("\n2. hand guiding, pushes up to 20 N, a surface while carrying 3.180 N")
    run = run_guiding(3.180, 20.0, seed=1, arm=arm)
    kinds = [e.kind for e in run.events if e.kind != "contact"]
    labels = np.array(run.labels)
    covered = [
        float(np.mean(labels[(run.times >= a) & (run.times <= b)] == "contact"))
        for a, b in (*run.pushes, run.surface)
    ]
    error = abs(run.mass_after / run.true_mass - 1) * 100
    print(f"   events but contacts: {kinds} {verdict(kinds == ['grasp', 'release'])}")
    print(
        "   share of each push / the surface labelled contact: "
        + ", ".join(f"{c:.2f}" for c in covered)
        + f" {verdict(min(covered) > 0.5)}"
    )
    print(f"   mass after them: error {error:.3f} % {verdict(error <= 0.5)}")


def cost(arm) -> None:
    print("\n3. cost per tick (CPU time, median of 41 alternating blocks)")
    truth = paper_like_truth()
    noise = SensorNoise.paper()
    gravity = truth.gravity_in_base / np.linalg.norm(truth.gravity_in_base) * truth.g
    q = np.array([0.2, -0.4, 1.6, 0.1, -0.9, 0.3])
    rotation = arm.rotation_sensor_to_base(q[None])[0]
    raw = truth.predict(rotation[None])[0] + 0.01
    plain = Compensator(truth, arm)
    loaded = Compensator(truth, arm, load=LoadTracker(noise, gravity))
    tracker = LoadTracker(noise, gravity)
    rows, contact = rotation.tolist(), plain.compensate(q, raw).tolist()
    floor, value, ratio = paired(
        lambda: plain.compensate(q, raw), lambda: tracker.tick(rows, contact)
    )
    print(
        f"   LoadTracker.tick {value * 1e6:.2f} µs vs Compensator.compensate {floor * 1e6:.2f} µs: "
        f"{ratio:.2f}x (<= 2x) {verdict(ratio <= 2.0)}"
    )
    floor, value, ratio = paired(
        lambda: plain.compensate(q, raw), lambda: loaded.compensate(q, raw)
    )
    print(
        f"   compensate with a load part {value * 1e6:.2f} µs vs without {floor * 1e6:.2f} µs: "
        f"{ratio:.2f}x"
    )


def placement(arm) -> None:
    print("\n4. placement by admittance, the 2.214 N object identified, the gripper closed")
    print(f"{'surface':<9}{'mass err %':>11}{'placed s':>10}{'truth s':>9}  events")
    for surface in (SPONGE, BOOK):
        run = run_placement(2.214, surface, arm=arm)
        error = abs(run.identified_mass / run.true_mass - 1) * 100
        kinds = [event.kind for event in run.events]
        gap = abs(run.placed_time - run.run.settle_time)
        ok = error <= 0.5 and kinds == ["grasp", "contact"] and gap <= 0.1
        print(
            f"{surface.name:<9}{error:>11.3f}{run.placed_time:>10.3f}{run.run.settle_time:>9.3f}"
            f"  {', '.join(kinds)} {verdict(ok)}"
        )


def main() -> None:
    arm = Arm.default()
    table4(arm)
    guiding(arm)
    cost(arm)
    placement(arm)


if __name__ == "__main__":
    from _targets import run_benchmark

    raise SystemExit(run_benchmark(main))
