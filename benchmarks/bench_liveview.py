"""What a LiveView costs a control loop, and how fast it draws.

Rows (median over repeats of the mean time per tick in a block of ticks;
the blocks of the different rows are interleaved so that a change of load on
the machine hits every row alike):

* ``step, view idle``: ``JointAdmittance.step`` of the placement experiment's
  controller (compensation on, noisy readings), the view process idle;
* ``step, view drawing``: the same, publishing only every 33rd tick (30 Hz at
  1 kHz), so the view process draws as it does in use: on a busy 2-core
  machine its CPU use slows the loop, which is not a cost of the tick;
* ``step + publish``: every tick ``view.publish(q, *controller.last_wrench_and_twist)``;
* ``wrapped step``: ``view.wrap(controller).step`` (publishes itself);
* ``publish alone`` and ``empty call`` (a Python method call that does
  nothing: the floor of any hook on the tick).

A second measure, robust to load swings: ticks alternate between ``step``
and ``step + publish`` and each tick is timed on its own (median per kind
over 20 000 ticks), the view process drawing throughout.

Then a 1 kHz loop paced with ``time.sleep`` runs for a few seconds and the
frames per second the view process drew are printed (target >= 20).

Target: ``step + publish`` - ``step, view drawing`` <= 1 µs.

Run: ``.venv/bin/python benchmarks/bench_liveview.py``
"""

from __future__ import annotations

import time

import numpy as np

from ftkin import Arm, SensorNoise
from ftkin.sim.placement import PlacementScenario, admittance_controller
from ftkin.sim.sensor import SimulatedSensor, paper_like_truth
from ftkin.viz import LiveView

BLOCK = 2000
"""Ticks per timed block."""

REPEATS = 21
"""Blocks per row."""


class _Empty:
    def hook(self, q, wrench, twist) -> None:
        pass


def main() -> None:
    arm = Arm.default()
    truth = paper_like_truth()
    controller = admittance_controller(PlacementScenario(), arm, truth)
    q = np.array([0.0, 0.3, 1.2, 0.0, 1.2, 0.0])
    sensor = SimulatedSensor(truth, SensorNoise.paper())
    rng = np.random.default_rng(0)
    raws = sensor.read(np.repeat(arm.rotation_sensor_to_base(q)[None], BLOCK, axis=0), rng)
    raws[:, 2] += 0.5  # N: a small contact so the arm moves
    dt = 1e-3
    clock = time.perf_counter

    with LiveView.for_controller(controller) as view:
        wrapped = view.wrap(controller)
        empty = _Empty()
        status = None

        def step_alone() -> None:
            for raw in raws:
                controller.step(q, raw, dt)

        def step_drawing() -> None:
            for i, raw in enumerate(raws):
                controller.step(q, raw, dt)
                if i % 33 == 0:
                    view.publish(q, *controller.last_wrench_and_twist)

        def step_publish() -> None:
            for raw in raws:
                controller.step(q, raw, dt)
                view.publish(q, *controller.last_wrench_and_twist)

        def step_wrapped() -> None:
            for raw in raws:
                wrapped.step(q, raw, dt)

        controller.step(q, raws[0], dt)
        status = controller.last_status
        wrench, twist = status.contact_wrench, status.twist

        def publish_alone() -> None:
            for _ in range(BLOCK):
                view.publish(q, wrench, twist)

        def empty_call() -> None:
            for _ in range(BLOCK):
                empty.hook(q, wrench, twist)

        def loop_floor() -> None:
            for _ in range(BLOCK):
                pass

        rows = {
            "step, view idle": step_alone,
            "step, view drawing": step_drawing,
            "step + publish": step_publish,
            "wrapped step": step_wrapped,
            "publish alone": publish_alone,
            "empty call": empty_call,
            "loop floor": loop_floor,
        }
        times = {name: [] for name in rows}
        for function in rows.values():
            function()  # warm-up
        for _ in range(REPEATS):
            for name, function in rows.items():
                controller.reset()
                start = clock()
                function()
                times[name].append((clock() - start) / BLOCK)
        median = {name: float(np.median(values)) * 1e6 for name, values in times.items()}
        floor = median.pop("loop floor")

        # Alternating ticks, each timed on its own.
        controller.reset()
        alternating = np.empty(20000)
        for i in range(len(alternating)):
            raw = raws[i % BLOCK]
            start = clock()
            controller.step(q, raw, dt)
            if i % 2:
                view.publish(q, *controller.last_wrench_and_twist)
            alternating[i] = clock() - start
        tick_alone = float(np.median(alternating[0::2])) * 1e6
        tick_publish = float(np.median(alternating[1::2])) * 1e6

        # A paced 1 kHz loop: how many frames does the view draw?
        controller.reset()
        seconds, ticks = 3.0, 0
        frames_before, start = view.frames_drawn, clock()
        q_run = q.copy()
        while clock() - start < seconds:
            dq = wrapped.step(q_run, raws[ticks % BLOCK], dt)
            q_run = q_run + dq * dt
            ticks += 1
            time.sleep(max(ticks * dt - (clock() - start), 0.0))
        elapsed = clock() - start
        fps = (view.frames_drawn - frames_before) / elapsed

    print(
        f"LiveView cost per control tick, bundled arm (median of {REPEATS} blocks of {BLOCK} ticks)"
    )
    print(f"{'row':<22}{'µs/tick':>10}")
    for name in ("step, view idle", "step, view drawing", "step + publish", "wrapped step"):
        print(f"{name:<22}{median[name]:>10.2f}")
    for name in ("publish alone", "empty call"):
        print(
            f"{name:<22}{median[name] - floor:>10.3f}   (loop overhead {floor:.3f} µs subtracted)"
        )
    added = median["step + publish"] - median["step, view drawing"]
    contention = median["step, view drawing"] - median["step, view idle"]
    print(
        f"{'publish adds':<22}{added:>10.2f}   target <= 1 µs: {'ok' if added <= 1.0 else 'MISSED'}"
        f" (publish alone: {'ok' if median['publish alone'] - floor <= 1.0 else 'MISSED'})"
    )
    print(
        f"alternating ticks, median of {len(alternating) // 2} each: step {tick_alone:.2f} µs, "
        "step + publish "
        f"{tick_publish:.2f} µs, publish adds {tick_publish - tick_alone:.2f} µs: "
        f"{'ok' if tick_publish - tick_alone <= 1.0 else 'MISSED'}"
    )
    print(
        f"{'drawing process':<22}{contention:>10.2f}   (CPU shared with the view process on this "
        "machine, not on the tick)"
    )
    print(
        f"paced 1 kHz loop for {elapsed:.1f} s ({ticks} ticks): the view drew {fps:.1f} frames/s, "
        "target >= 20: "
        f"{'ok' if fps >= 20 else 'MISSED'}"
    )


if __name__ == "__main__":
    from _targets import run_benchmark

    raise SystemExit(run_benchmark(main))
