"""``ftkin simulate placement``: the paper's placement experiment on the bundled arm.

(``ftkin simulate samples|log|recording|bag``, example inputs, are in
:mod:`ftkin.cli.simulate_inputs`.)

Gains are given as in the paper, k13 [mm/N] and k23 [mm/(s·N)], and converted
to SI. The CSV has one row per control tick: ``t`` [s], ``displacement`` (tool
z from the start) [m], ``velocity`` [m/s], ``force`` (true compensated F'z,
sensor z pointing down) [N], ``measured_force`` (what the controller saw) [N],
``penetration`` [m], ``normal_force`` [N]; with ``--sweep`` a first column
``gain`` holds the swept value [mm/N or mm/(s·N)], with ``--mode all`` a first
column ``mode`` the index of the mode in ``position, admittance,
admittance-uncompensated``.

``--engine mujoco`` (the default when the ``sim`` extra is installed) runs the
experiment in MuJoCo (:mod:`ftkin.sim.mujoco`): servoed arm, inertia, a
spring-loaded pad, a sensor with bias, noise and a one-tick delay. Its CSV adds
the joint states ``q1..`` [rad], ``dq1..`` [rad/s], the commands ``cmd1..``
[rad/s], the ideal load on the sensor ``ideal_fx..ideal_mz`` [N, N·m] and
``held`` (1 when the controller held the arm). ``--engine simple`` keeps the
kinematic arm and the spring-damper formula (:mod:`ftkin.sim.placement`).
"""

from __future__ import annotations

import importlib.util
from dataclasses import replace

import numpy as np

from ..exceptions import InvalidInput
from ..io.csv_table import write_csv
from ..sim.placement import MODES, PlacementRun, PlacementScenario, simulate_placement
from ..sim.surfaces import SURFACES, surface_by_name
from .arg_types import bounded_int, non_negative_float, positive_float, seed
from .simulate_inputs import add_input_parsers

_DEFAULT = PlacementScenario()


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "simulate",
        help="simulated experiments (the paper's placement test) and example inputs (samples, "
        "log, recording, bag)",
    )
    experiments = parser.add_subparsers(dest="experiment", metavar="EXPERIMENT", required=True)
    placement = experiments.add_parser(
        "placement",
        help="lower a grasped object onto a sponge or a book: position vs admittance control",
        description="Lower a grasped object onto a surface with position control, admittance "
        "control with "
        "compensation, or admittance control on raw readings (docs/method.md §6).",
    )
    _add_scenario_arguments(placement)
    _add_run_arguments(placement)
    placement.set_defaults(func=run)
    add_input_parsers(experiments)


def _add_scenario_arguments(placement) -> None:
    """The experiment: surface, controller, gains, object, timing."""
    placement.add_argument("--surface", choices=sorted(SURFACES), default="sponge")
    placement.add_argument(
        "--mode",
        choices=(*MODES, "all"),
        default="admittance",
        help="controller; 'all' runs the three and plots them together (default: %(default)s)",
    )
    placement.add_argument(
        "--k1",
        type=non_negative_float,
        default=_DEFAULT.k1 * 1e3,
        metavar="MM_PER_N",
        help="position gain k13 [mm/N] (default: %(default)g)",
    )
    placement.add_argument(
        "--k2",
        type=non_negative_float,
        default=_DEFAULT.k2 * 1e3,
        metavar="MM_PER_S_N",
        help="velocity gain k23 [mm/(s·N)] (default: %(default)g; the paper swept around 0.1)",
    )
    placement.add_argument(
        "--weight",
        type=positive_float,
        default=_DEFAULT.object_weight,
        help="object weight [N] (default: %(default)g)",
    )
    placement.add_argument(
        "--gap",
        type=non_negative_float,
        default=_DEFAULT.start_gap * 1e3,
        help="object bottom above the surface at the start [mm] (default: %(default)g)",
    )
    placement.add_argument(
        "--duration",
        type=positive_float,
        default=_DEFAULT.duration,
        help="simulated time [s] (default: %(default)g)",
    )
    placement.add_argument(
        "--dt",
        type=positive_float,
        default=_DEFAULT.dt,
        help="control period [s] (default: %(default)g)",
    )
    placement.add_argument(
        "--seed",
        type=seed,
        default=0,
        help="random seed of the sensor noise (default: %(default)s)",
    )


def _add_run_arguments(placement) -> None:
    """How it runs (engine, sensor timing, sweep) and what it writes."""
    placement.add_argument(
        "--engine",
        choices=ENGINES,
        default=default_engine(),
        help="mujoco (physics engine, extra 'sim') or simple (kinematic arm, spring-damper "
        "formula); "
        "default: mujoco when installed (here: %(default)s)",
    )
    placement.add_argument(
        "--sample-rate",
        type=positive_float,
        metavar="HZ",
        help="MuJoCo engine: sensor sample rate [Hz] (default: one sample per control tick)",
    )
    placement.add_argument(
        "--delay-ticks",
        type=bounded_int(0, 10_000, "ticks"),
        default=1,
        metavar="N",
        help="MuJoCo engine: sensor delay in control ticks (default: %(default)s)",
    )
    placement.add_argument(
        "--sweep", choices=("k1", "k2"), help="repeat the run over --values of this gain"
    )
    placement.add_argument(
        "--values",
        type=_value_list,
        metavar="V1,V2,...",
        help="gain values for --sweep, in the paper's mm units (e.g. 0.05,0.1,0.2)",
    )
    placement.add_argument("-o", "--output", metavar="RUN.csv", help="write the time series")
    placement.add_argument(
        "--plot",
        metavar="RUN.png",
        help="write displacement, velocity and force plots (needs matplotlib)",
    )
    placement.add_argument(
        "--view",
        action="store_true",
        help="watch the run live in meshcat (arm, contact wrench, commanded twist), paced to real "
        "time",
    )


ENGINES = ("mujoco", "simple")
"""Simulation engines of ``ftkin simulate placement``."""


def default_engine() -> str:
    """``"mujoco"`` when the ``mujoco`` package is importable, else ``"simple"``."""
    return "mujoco" if importlib.util.find_spec("mujoco") is not None else "simple"


def _value_list(text: str) -> list[float]:
    return [non_negative_float(part) for part in text.split(",") if part.strip()]


def _summary(run: PlacementRun) -> str:
    settle = run.settle_time
    placed = (
        f"placed at t = {settle:.3f} s"
        if np.isfinite(settle)
        else "not placed (|F'z| >= 0.05 N or still moving at the end)"
    )
    return (
        f"peak contact force {run.peak_contact_force:.3f} N, final F'z {run.final_force:+.3f} N, "
        f"final penetration {run.penetration[-1] * 1e3:.3f} mm; {placed}"
    )


def _simulate(scenario: PlacementScenario, args):
    """``(PlacementRun, header, rows)`` of one run on the chosen engine."""
    if args.engine == "simple":
        run_ = simulate_placement(scenario)
        return run_, list(PlacementRun.COLUMNS), run_.rows()
    from ..sim.mujoco.mujoco_placement import simulate_placement_mujoco

    run_, full = simulate_placement_mujoco(
        scenario, sample_rate=args.sample_rate, delay_ticks=args.delay_ticks
    )
    for time, event in full.events:
        if event:
            print(f"  t = {time:.3f} s: {event}")
    return run_, list(full.columns), full.table


def _run_viewed(scenario: PlacementScenario) -> PlacementRun:
    """One run drawn by a LiveView, each tick published and paced to the wall clock."""
    import time

    from ..kinematics.arm import Arm
    from ..sim.placement import admittance_controller
    from ..viz.live import LiveView

    arm = Arm.default()
    frame = admittance_controller(scenario, arm, None).frame
    with LiveView(arm, control_frame=frame) as view:
        print(f"live view: {view.url}")
        start, ticks = time.perf_counter(), [0]

        def on_tick(q, wrench, twist):
            view.publish(q, wrench, twist)
            ticks[0] += 1
            ahead = ticks[0] * scenario.dt - (time.perf_counter() - start)
            if ahead > 0.002:
                time.sleep(ahead)

        result = simulate_placement(scenario, arm, on_tick=on_tick)
        time.sleep(0.2)  # let the last state be drawn
        print(f"drew {view.frames_drawn} frames in {time.perf_counter() - start:.1f} s")
    return result


def _scenario(args) -> PlacementScenario:
    return PlacementScenario(
        surface=surface_by_name(args.surface),
        mode=MODES[0] if args.mode == "all" else args.mode,
        k1=args.k1 * 1e-3,
        k2=args.k2 * 1e-3,
        object_weight=args.weight,
        start_gap=args.gap * 1e-3,
        duration=args.duration,
        dt=args.dt,
        seed=args.seed,
    )


def _scenarios(args, scenario: PlacementScenario) -> tuple[list[PlacementScenario], list]:
    """The runs the options ask for and their labels (gain values or mode indices)."""
    if args.view and (args.sweep or args.mode in ("position", "all")):
        raise InvalidInput(
            "--view draws one run of an admittance controller: drop --sweep, use --mode admittance"
        )
    if args.sweep:
        if not args.values:
            raise InvalidInput("--sweep needs --values, e.g. --values 0.05,0.1,0.2 (mm units)")
        if args.mode in ("position", "all"):
            raise InvalidInput(
                "--sweep varies admittance gains; use --mode admittance or admittance-uncompensated"
            )
        scenarios = [replace(scenario, **{args.sweep: value * 1e-3}) for value in args.values]
        return scenarios, list(args.values)
    if args.values:
        raise InvalidInput("--values needs --sweep k1 or --sweep k2")
    modes = MODES if args.mode == "all" else (args.mode,)
    return [replace(scenario, mode=mode) for mode in modes], list(range(len(modes)))


def _write(args, results, labels) -> None:
    """The time series (``-o``) and the plots (``--plot``) of the runs."""
    runs = [result[0] for result in results]
    if args.output:
        header = results[0][1]
        if len(results) > 1:
            header = ["gain" if args.sweep else "mode"] + header
            rows = [
                [label, *row]
                for label, result in zip(labels, results)
                for row in result[2].tolist()
            ]
        else:
            rows = results[0][2].tolist()
        write_csv(args.output, header, rows)
        print(f"wrote {args.output}")
    if args.plot:
        from ..sim.placement_plots import plot_runs, plot_sweep

        title = f"Placement on the {args.surface}, {args.mode} ({args.engine})"
        if args.sweep:
            plot_sweep(runs, args.sweep, args.plot, title)
        else:
            plot_runs(runs, args.plot, title)
        print(f"wrote {args.plot}")


def run(args) -> int:
    scenarios, labels = _scenarios(args, _scenario(args))
    if args.view:  # the live view draws the simple engine's run, paced to the wall clock
        if args.engine != "simple":
            print("--view: running the simple engine (the live view follows its ticks)")
            args.engine = "simple"  # the labels below say what ran
        viewed = _run_viewed(scenarios[0])
        results = [(viewed, list(PlacementRun.COLUMNS), viewed.rows())]
    else:
        results = [_simulate(one, args) for one in scenarios]
    for one, _, _ in results:
        prefix = (
            f"{'k13' if args.sweep == 'k1' else 'k23'} = "
            f"{getattr(one.scenario, args.sweep) * 1e3:g}: "
            if args.sweep
            else ""
        )
        print(f"{args.surface}, {one.scenario.mode} ({args.engine}): {prefix}{_summary(one)}")
    _write(args, results, labels)
    return 0
