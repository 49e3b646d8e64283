"""Soak of the control path: ``JointAdmittance.step`` for a million ticks of placement cycles.

The bundled arm holds the paper's object (2.214 N, 40 mm below the tool
point) over a compliant surface, with :mod:`ftkin.sim.placement`'s default
scenario, controller and contact model: the admittance (tool z only,
desired force 0) lowers the object onto the surface
until it carries the weight ("place", 4 s), then a desired force of -8 N
along the tool z lifts it back to the cycle's start height ("lift"); the
next cycle puts a new surface (sponge and book in turn) 1-4 mm below the
object. The simulated sensor (paper-like bias, tool weight and noise) reads
the object's weight and the surface's normal force with their moments. The
arm is kinematic (``q ← q + dq·dt``); to keep the simulation cheap the
reading of a tick uses the sensor pose the previous ``step`` computed (one
tick, a few µm, behind).

Every ``--fault-every`` ticks a fault is injected, in turn: a NaN in the
reading, a NaN in ``q``, a saturated fz (300 N, 3 ticks), a dt jump
(20 ms), a stuck sensor (the reading repeated for 25 ticks). Each must be
reported (one onset per injection) and nothing else.

Measured: the latency of every ``step`` call (percentiles in µs); the
process RSS (``/proc/self/status`` VmRSS) after warm-up, every 100,000 ticks
and at the end; the count of gc-tracked objects; and, since tracemalloc
slows the step about 4x, a traced window of ``--trace-ticks`` extra ticks at
the end (Python heap 1,000 ticks into it and at its end, and peak). The
latency and flag buffers are written through before the baseline so their
pages count from the start. Fails (exit 1) on a NaN
``dq``, a missed or spurious fault, a safety stop, RSS growth over
``--max-rss-growth`` MB or traced growth over 100 kB.

Run: ``.venv/bin/python benchmarks/soak_control.py`` (``--ticks 1000000``).
"""

from __future__ import annotations

import argparse
import gc
import time
import tracemalloc

import numpy as np

from ftkin import Arm, Compensator
from ftkin.control.sensor_faults import SensorFault
from ftkin.sim.placement import Q_DOWN, PlacementScenario, admittance_controller
from ftkin.sim.sensor import paper_like_truth
from ftkin.sim.surfaces import BOOK, SPONGE, held_object_wrench

SCENARIO = PlacementScenario()  # the paper's object, gains, deadband and noise
DT = SCENARIO.dt  # control period [s]
WEIGHT, HEIGHT = (
    SCENARIO.object_weight,
    SCENARIO.object_height,
)  # [N], object bottom below the tool point [m]
PLACE_TICKS = 4000  # ticks of the place phase
LIFT_FORCE = -8.0  # desired tool-z force while lifting [N]
WARMUP = 20_000  # ticks before the memory baseline
CHUNK = 100_000  # ticks per block of pre-drawn noise, and per RSS checkpoint
INJECTIONS = (
    ("nan raw", SensorFault.NOT_FINITE, 1),
    ("nan q", SensorFault.NOT_FINITE, 1),
    ("saturated fz", SensorFault.SATURATED, 3),
    ("dt jump", SensorFault.DT_JUMP, 1),
    ("stuck", SensorFault.STUCK, 25),
)


def rss_kib() -> int:
    """Resident set size of this process [KiB]."""
    with open("/proc/self/status") as status:
        for line in status:
            if line.startswith("VmRSS:"):
                return int(line.split()[1])
    return 0


class PlacementCycles:
    """The simulated world: arm, object, surfaces, sensor, and the cycle's phase."""

    def __init__(self, seed: int = 0):
        self.arm = arm = Arm.default()
        truth = paper_like_truth()
        self.rng = np.random.default_rng(seed)
        self.noise_std = SCENARIO.noise.channel_std
        self.controller = admittance_controller(SCENARIO, arm, truth)
        self.unloaded = Compensator(truth)  # -compensate(R, 0) = bias + tool gravity
        self._zero = np.zeros(6)
        self.q = np.array(Q_DOWN)
        rotation, origin = arm.frame_placement(self.q, "sensor")
        _, tool = arm.frame_placement(self.q, "tool")
        self.tool_in_sensor = rotation.T @ (tool - origin)
        self.rotation, self.origin = rotation, origin
        self.start_height = tool[2]
        self.lifting, self.phase_ticks, self.cycles, self.placed = False, 0, 0, 0
        self.penetration_before, self.normal = 0.0, 0.0
        self._new_surface()

    def _new_surface(self) -> None:
        bottom = self.origin + self.rotation @ self.tool_in_sensor + self.rotation[:, 2] * HEIGHT
        surface = (SPONGE, BOOK)[self.cycles % 2]
        self.surface = surface.at_height(bottom[2] - self.rng.uniform(0.001, 0.004))
        self.controller.admittance.desired_wrench[2] = 0.0
        self.lifting, self.phase_ticks = False, 0

    def reading(self, noise: np.ndarray) -> np.ndarray:
        """Raw reading [N, N·m] at the current pose (the pose of the last computed step)."""
        rotation, origin = self.rotation, self.origin
        tool = origin + rotation @ self.tool_in_sensor
        penetration = max(0.0, self.surface.height - (tool[2] + rotation[2, 2] * HEIGHT))
        normal = self.surface.normal_force(
            penetration, (penetration - self.penetration_before) / DT
        )
        self.penetration_before, self.normal = penetration, normal
        contact = held_object_wrench(rotation, origin, tool, HEIGHT, WEIGHT, normal)
        return contact - self.unloaded.compensate_unchecked(rotation, self._zero) + noise

    def advance(self, dq: np.ndarray) -> None:
        """Integrate ``dq`` and run the cycle's phase logic."""
        placement = self.controller._data.oMf[self.controller._sensor_id]
        self.rotation, self.origin = placement.rotation.copy(), placement.translation.copy()
        self.q = self.q + dq * DT
        self.phase_ticks += 1
        if not self.lifting and self.phase_ticks >= PLACE_TICKS:
            self.lifting, self.phase_ticks = True, 0
            self.placed += (
                abs(self.normal - WEIGHT) < 0.1
            )  # the surface carries the object's weight
            self.controller.admittance.desired_wrench[2] = LIFT_FORCE
        elif (
            self.lifting
            and (self.origin + self.rotation @ self.tool_in_sensor)[2] >= self.start_height
        ):
            self.cycles += 1
            self._new_surface()


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--ticks", type=float, default=1e6, help="control ticks (default 1e6)")
    parser.add_argument(
        "--fault-every", type=int, default=10_007, help="ticks between injected faults"
    )
    parser.add_argument(
        "--trace-ticks", type=int, default=50_000, help="extra ticks under tracemalloc"
    )
    parser.add_argument(
        "--max-rss-growth", type=float, default=4.0, help="allowed RSS growth after warm-up [MB]"
    )
    args = parser.parse_args(argv)
    ticks = int(args.ticks)
    world = PlacementCycles()
    controller = world.controller
    # Record buffers written through now, so their pages are resident before the memory baseline.
    latency = np.empty(ticks + args.trace_ticks, dtype=np.int64)
    held = np.empty(ticks + args.trace_ticks, dtype=bool)
    latency.fill(0)
    held.fill(False)
    noise = np.empty((CHUNK, 6))
    injected = {name: 0 for name, _, _ in INJECTIONS}
    onsets = {fault: 0 for fault in SensorFault if fault is not SensorFault.NONE}
    rss, objects, traced = {}, {}, {}
    injection, remaining, stuck_raw, previous_fault = None, 0, None, SensorFault.NONE
    nan_returned, clock = 0, time.perf_counter_ns
    wall = time.perf_counter()
    for tick in range(ticks + args.trace_ticks):
        if tick % CHUNK == 0:
            world.rng.standard_normal(out=noise)
            noise *= world.noise_std
        if tick == WARMUP:
            gc.collect()
            rss["start"], objects["start"] = rss_kib(), len(gc.get_objects())
        if tick > WARMUP and tick % CHUNK == 0 and tick <= ticks:
            rss[tick] = rss_kib()
        if tick == ticks:
            gc.collect()
            rss["end"], objects["end"] = rss_kib(), len(gc.get_objects())
            tracemalloc.start()
        if tick == ticks + min(
            1000, args.trace_ticks // 10
        ):  # after the traced objects' first allocations
            traced["start"] = tracemalloc.get_traced_memory()[0]
        q, raw, dt = world.q, world.reading(noise[tick % CHUNK]), DT
        if remaining == 0 and tick > WARMUP and tick % args.fault_every == 0:
            injection = INJECTIONS[sum(injected.values()) % len(INJECTIONS)]
            injected[injection[0]] += 1
            remaining, stuck_raw = injection[2], raw
        if remaining:
            remaining -= 1
            name = injection[0]
            if name == "nan raw":
                raw[1] = np.nan
            elif name == "nan q":
                q = q.copy()
                q[4] = np.nan
            elif name == "saturated fz":
                raw[2] = 300.0
            elif name == "dt jump":
                dt = 20 * DT
            else:
                raw = stuck_raw
        start = clock()
        dq = controller.step(q, raw, dt)
        latency[tick] = clock() - start
        fault = controller.last_status.fault
        held[tick] = fault is not SensorFault.NONE
        if fault is not SensorFault.NONE and previous_fault is SensorFault.NONE:
            onsets[fault] += 1
        previous_fault = fault
        if not np.isfinite(dq).all():
            nan_returned += 1
            dq = np.zeros(6)
        world.advance(dq)
    traced["end"], traced["peak"] = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    wall = time.perf_counter() - wall
    return report(
        args,
        ticks,
        world,
        latency,
        held,
        injected,
        onsets,
        rss,
        objects,
        traced,
        nan_returned,
        wall,
    )


def report(
    args, ticks, world, latency, held, injected, onsets, rss, objects, traced, nan_returned, wall
) -> int:
    """Print the tables; the exit code (1 when a check failed)."""
    micro = latency[:ticks] / 1e3
    print(
        f"soak: {ticks:,} ticks + {args.trace_ticks:,} traced, {world.cycles} placement cycles "
        f"({ticks * DT:.0f} s simulated) in {wall:.1f} s wall; object placed (surface carries it "
        f"within 0.1 N at the end of the place phase) in {world.placed} of "
        f"{world.cycles + world.lifting} cycles"
    )
    print(
        f"\n{'step latency [µs]':<26}{'ticks':>9}{'p50':>8}{'p90':>8}{'p99':>8}{'p99.9':>8}"
        f"{'max':>9}{'mean':>8}"
    )
    for name, values in (
        ("all ticks", micro),
        ("moving ticks", micro[~held[:ticks]]),
        ("held (fault) ticks", micro[held[:ticks]]),
    ):
        if values.size:
            p50, p90, p99, p999 = np.percentile(values, [50, 90, 99, 99.9])
            print(
                f"{name:<26}{values.size:>9}{p50:>8.1f}{p90:>8.1f}{p99:>8.1f}{p999:>8.1f}"
                f"{values.max():>9.1f}{values.mean():>8.1f}"
            )
    expected = {
        SensorFault.NOT_FINITE: injected["nan raw"] + injected["nan q"],
        SensorFault.SATURATED: injected["saturated fz"],
        SensorFault.DT_JUMP: injected["dt jump"],
        SensorFault.STUCK: injected["stuck"],
    }
    print(f"\n{'fault':<14}{'injected':>9}{'reported':>9}{'held ticks':>11}")
    for fault, count in expected.items():
        print(
            f"{fault.value:<14}{count:>9}{onsets[fault]:>9}"
            f"{world.controller.monitor.counts[fault]:>11}"
        )
    growth = (rss["end"] - rss["start"]) / 1024
    peak_rss = max(value for value in rss.values())
    traced_growth = traced["end"] - traced["start"]
    print(f"\n{'memory':<44}{'start':>12}{'end':>12}{'growth':>12}")
    print(
        f"{'RSS [MB] (after warm-up .. end of ticks)':<44}{rss['start'] / 1024:>12.2f}"
        f"{rss['end'] / 1024:>12.2f}{growth:>12.2f}"
    )
    print(
        f"{'gc-tracked objects':<44}{objects['start']:>12}{objects['end']:>12}"
        f"{objects['end'] - objects['start']:>12}"
    )
    print(
        f"{'tracemalloc [kB] (traced window)':<44}{traced['start'] / 1e3:>12.1f}"
        f"{traced['end'] / 1e3:>12.1f}"
        f"{traced_growth / 1e3:>12.1f}   peak {traced['peak'] / 1e3:.1f} kB"
    )
    checkpoints = [value for key, value in rss.items() if isinstance(key, int)]
    if checkpoints:
        print(
            "RSS every 100,000 ticks [MB]: "
            + " ".join(f"{value / 1024:.1f}" for value in checkpoints)
        )
    print(
        f"RSS max over checkpoints: {peak_rss / 1024:.2f} MB; NaN dq returned: {nan_returned}; "
        f"safety stop: {world.controller.safety_latched}"
    )
    failures = []
    if nan_returned:
        failures.append(f"{nan_returned} NaN dq")
    if any(onsets[fault] != count for fault, count in expected.items()):
        failures.append("faults reported differ from those injected")
    if world.controller.safety_latched:
        failures.append("safety stop fired")
    if growth > args.max_rss_growth:
        failures.append(f"RSS grew {growth:.2f} MB > {args.max_rss_growth} MB")
    if traced_growth > 100e3:
        failures.append(f"traced heap grew {traced_growth / 1e3:.1f} kB")
    print("FAIL: " + "; ".join(failures) if failures else "PASS")
    return 1 if failures else 0


if __name__ == "__main__":
    from _targets import run_benchmark

    raise SystemExit(run_benchmark(main))
