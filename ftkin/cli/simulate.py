"""``ftkin simulate placement|samples|log|recording|bag``: the paper's placement experiment on the
bundled arm, and example inputs from the simulated sensor.

Placement gains are given as in the paper, k13 [mm/N] and k23 [mm/(s·N)], and converted
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

``samples``, ``log``, ``recording`` and ``bag`` each write a file the matching
command reads, from known parameters (:mod:`ftkin.sim.inputs`): the paper-like
tool and bias (:func:`~ftkin.sim.sensor.paper_like_truth`) unless
``--tool-mass``/``--com`` say otherwise, the paper's noise times
``--noise-scale``, and optionally a drifting bias, a mount rotation on the
flange or a reversed sign. The truth is printed, so what ``ftkin calibrate``
finds can be compared with it.
"""

import importlib.util
import time
from dataclasses import replace

import numpy as np

from .. import Arm, InvalidInput
from ..io.calibration_file import MAX_COM_DISTANCE
from ..io.csv_table import read_table, write_csv
from ..io.samples_csv import configurations_from_table
from ..sim import inputs as sim_inputs
from ..sim.placement import (
    MODES,
    PlacementRun,
    PlacementScenario,
    admittance_controller,
    simulate_placement,
)
from ..sim.surfaces import SURFACES, surface_by_name
from .arg_types import (
    add_command,
    add_options,
    bounded_int,
    non_negative_float,
    number_list,
    option,
    positive_float,
    refuse,
)
from .common import add_arm_arguments, arm_from_args
from .pose_options import READINGS_PER_POSE
from .shared_options import (
    CENTER_OF_MASS,
    DEFAULT_POSES,
    DURATION,
    POSES,
    POSES_FILE,
    SEED,
    SENSOR_SIGN,
    TOOL_MASS,
    resolved,
)

_DEFAULT = PlacementScenario()


def _value_list(text: str) -> list[float]:
    return [non_negative_float(part) for part in text.split(",") if part.strip()]


# simulate placement: the experiment (surface, controller, gains, object, timing), how it runs
# (engine, sensor timing, sweep) and what it writes.
_PLACEMENT_OPTIONS = (
    option("--surface", choices=sorted(SURFACES), default="sponge"),
    option(
        "--mode",
        choices=(*MODES, "all"),
        default="admittance",
        help="controller; 'all' runs the three and plots them together (default: %(default)s)",
    ),
    option(
        "--k1",
        type=non_negative_float,
        default=_DEFAULT.k1 * 1e3,
        metavar="MM_PER_N",
        help="position gain k13 [mm/N] (default: %(default)g)",
    ),
    option(
        "--k2",
        type=non_negative_float,
        default=_DEFAULT.k2 * 1e3,
        metavar="MM_PER_S_N",
        help="velocity gain k23 [mm/(s·N)] (default: %(default)g; the paper swept around 0.1)",
    ),
    option(
        "--weight",
        type=positive_float,
        default=_DEFAULT.object_weight,
        help="object weight [N] (default: %(default)g)",
    ),
    option(
        "--gap",
        type=non_negative_float,
        default=_DEFAULT.start_gap * 1e3,
        help="object bottom above the surface at the start [mm] (default: %(default)g)",
    ),
    DURATION,
    option(
        "--dt",
        type=positive_float,
        default=_DEFAULT.dt,
        help="control period [s] (default: %(default)g)",
    ),
    SEED,
    option(
        "--engine",
        choices=("mujoco", "simple"),
        default="mujoco" if importlib.util.find_spec("mujoco") is not None else "simple",
        help="mujoco (physics engine, extra 'sim') or simple (kinematic arm, spring-damper "
        "formula); "
        "default: mujoco when installed (here: %(default)s)",
    ),
    option(
        "--sample-rate",
        type=positive_float,
        metavar="HZ",
        help="MuJoCo engine: sensor sample rate [Hz] (default: one sample per control tick)",
    ),
    option(
        "--delay-ticks",
        type=bounded_int(0, 10_000, "ticks"),
        default=1,
        metavar="N",
        help="MuJoCo engine: sensor delay in control ticks (default: %(default)s)",
    ),
    option("--sweep", choices=("k1", "k2"), help="repeat the run over --values of this gain"),
    option(
        "--values",
        type=_value_list,
        metavar="V1,V2,...",
        help="gain values for --sweep, in the paper's mm units (e.g. 0.05,0.1,0.2)",
    ),
    option("-o", "--output", metavar="RUN.csv", help="write the time series"),
    option(
        "--plot",
        metavar="RUN.png",
        help="write displacement, velocity and force plots (needs matplotlib)",
    ),
    option(
        "--view",
        action="store_true",
        help="watch the run live in meshcat (arm, contact wrench, commanded twist), paced "
        "to real time",
    ),
)


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "simulate",
        help="simulated experiments (the paper's placement test) and example inputs (samples, "
        "log, recording, bag)",
    )
    experiments = parser.add_subparsers(dest="experiment", metavar="EXPERIMENT", required=True)
    add_command(
        experiments,
        "placement",
        help="lower a grasped object onto a sponge or a book: position vs admittance control",
        description="Lower a grasped object onto a surface with position control, admittance "
        "control with "
        "compensation, or admittance control on raw readings (docs/method.md §6).",
        options=_PLACEMENT_OPTIONS,
        run=run,
    )
    # the example inputs, each from the simulated sensor and tool
    for kind, text in KINDS.items():
        parser = experiments.add_parser(kind, help=text, description=f"Write {text}.")
        add_options(parser.add_argument_group("the simulated sensor and tool"), *SENSOR_OPTIONS)
        add_arm_arguments(parser)
        add_options(
            parser,
            *INPUT_OPTIONS[kind],
            option("-o", "--output", required=True, metavar="FILE", help="file to write"),
        )
        parser.set_defaults(func=run_input, kind=kind)


def _simulate(scenario: PlacementScenario, args):
    """``(PlacementRun, header, rows)`` of one run on the chosen engine."""
    if args.engine == "simple":  # with --view, drawn live
        run_ = _run_viewed(scenario) if args.view else simulate_placement(scenario)
        return run_, list(PlacementRun.COLUMNS), run_.rows()
    from ..sim.mujoco.mujoco_placement import simulate_placement_mujoco

    run_, full = simulate_placement_mujoco(
        scenario, sample_rate=args.sample_rate, delay_ticks=args.delay_ticks
    )
    for at, event in full.events:
        if event:
            print(f"  t = {at:.3f} s: {event}")
    return run_, list(full.columns), full.table


def _run_viewed(scenario: PlacementScenario) -> PlacementRun:
    """One run drawn by a LiveView, each tick published and paced to the wall clock."""
    from ..viz.live import LiveView

    arm = Arm.default()
    with LiveView(arm, control_frame=admittance_controller(scenario, arm, None).frame) as view:
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


def _scenarios(args) -> tuple[list[PlacementScenario], list]:
    """The runs the options ask for and their labels (gain values or mode indices)."""
    if args.view and (args.sweep or args.mode in ("position", "all")):
        raise InvalidInput(
            "--view draws one run of an admittance controller: drop --sweep, use --mode admittance"
        )
    scenario = PlacementScenario(
        surface=surface_by_name(args.surface),
        mode=MODES[0] if args.mode == "all" else args.mode,
        k1=args.k1 * 1e-3,
        k2=args.k2 * 1e-3,
        object_weight=args.weight,
        start_gap=args.gap * 1e-3,
        duration=resolved(args.duration, _DEFAULT.duration),
        dt=args.dt,
        seed=args.seed,
    )
    refuse(
        InvalidInput,
        (
            args.sweep and not args.values,
            "--sweep needs --values, e.g. --values 0.05,0.1,0.2 (mm units)",
        ),
        (
            args.sweep and args.mode in ("position", "all"),
            "--sweep varies admittance gains; use --mode admittance or admittance-uncompensated",
        ),
        (args.values and not args.sweep, "--values needs --sweep k1 or --sweep k2"),
    )
    if args.sweep:
        scenarios = [replace(scenario, **{args.sweep: value * 1e-3}) for value in args.values]
        return scenarios, list(args.values)
    modes = MODES if args.mode == "all" else (args.mode,)
    return [replace(scenario, mode=mode) for mode in modes], list(range(len(modes)))


def _write(args, results, labels) -> None:
    """The time series (``-o``) and the plots (``--plot``) of the runs."""
    runs = [result[0] for result in results]
    if args.output:
        header, rows = results[0][1], results[0][2].tolist()
        if len(results) > 1:
            header = ["gain" if args.sweep else "mode"] + header
            rows = [
                [label, *row]
                for label, result in zip(labels, results)
                for row in result[2].tolist()
            ]
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
    scenarios, labels = _scenarios(args)
    # the live view draws the simple engine's run (one scenario), paced to the wall clock
    if args.view and args.engine != "simple":
        print("--view: running the simple engine (the live view follows its ticks)")
        args.engine = "simple"  # the labels below say what ran
    results = [_simulate(one, args) for one in scenarios]
    for one, _, _ in results:
        prefix = (
            f"{'k13' if args.sweep == 'k1' else 'k23'} = "
            f"{getattr(one.scenario, args.sweep) * 1e3:g}: "
            if args.sweep
            else ""
        )
        placed = (
            f"placed at t = {one.settle_time:.3f} s"
            if np.isfinite(one.settle_time)
            else "not placed (|F'z| >= 0.05 N or still moving at the end)"
        )
        print(
            f"{args.surface}, {one.scenario.mode} ({args.engine}): {prefix}peak contact force "
            f"{one.peak_contact_force:.3f} N, final F'z {one.final_force:+.3f} N, final "
            f"penetration {one.penetration[-1] * 1e3:.3f} mm; {placed}"
        )
    _write(args, results, labels)
    return 0


KINDS = {
    "samples": "a samples CSV at static poses (for ftkin calibrate)",
    "log": "a log of a slow move with a known 2 N push on the tool (for ftkin compensate)",
    "recording": "a moving recording along an excitation, MuJoCo inverse dynamics (for "
    "ftkin calibrate --dynamic; extra 'sim'; a URDF with a 'gripper' link on the sensor, such as "
    "the bundled arm's)",
    "bag": "a ROS 2 bag (MCAP) of a session holding each pose (for ftkin calibrate BAG and "
    "ftkin extract; extra 'bags')",
}
"""The example inputs ``ftkin simulate`` writes, and what each is for."""


_POSES = (POSES_FILE, POSES)
INPUT_OPTIONS = {
    "samples": (*_POSES, READINGS_PER_POSE),
    "log": (DURATION,),
    "recording": (
        DURATION,
        option(
            "--trajectory",
            metavar="TRAJ.csv",
            help="excitation to follow (ftkin plan --excitation -o TRAJ.csv; default: one "
            "planned for --duration)",
        ),
    ),
    "bag": _POSES,
}
"""The options of each example input of ``ftkin simulate``, besides the sensor's and the arm's."""

SENSOR_OPTIONS = (
    SEED,
    TOOL_MASS,
    CENTER_OF_MASS,
    option(
        "--noise-scale",
        type=positive_float,
        default=1.0,
        metavar="K",
        help="noise = K × the paper's 0.02 N, 0.002 N·m per reading (default: %(default)g)",
    ),
    option(
        "--with-drift",
        dest="with_drift",
        action="store_true",
        help="a drifting bias (warm-up and random walk, SensorDrift.typical()); samples get a "
        "t column",
    ),
    option(
        "--mount-rpy-deg",
        type=number_list,
        metavar="R P Y",
        help="the sensor turned on the flange: R_M = Rz(Y) Ry(P) Rx(R) [deg]",
    ),
    SENSOR_SIGN,
)
"""The simulated sensor and tool of every example input."""


def _inputs(args):
    from .. import SensorModel, SensorNoise
    from ..kinematics.rotations import euler_zyx_to_matrix
    from ..sim import SensorDrift
    from ..sim.sensor import paper_like_truth

    refuse(
        InvalidInput,
        (
            args.com is not None and len(args.com) != 3,
            f"--com takes X Y Z [m], got {len(args.com or ())} numbers",
        ),
        (
            args.mount_rpy_deg is not None and len(args.mount_rpy_deg) != 3,
            f"--mount-rpy-deg takes R P Y [deg], got {args.mount_rpy_deg}",
        ),
        (  # the tool a calibration file would accept (a COM farther is a unit mistake)
            args.com is not None and float(np.linalg.norm(args.com)) > MAX_COM_DISTANCE,
            f"--com {' '.join(f'{v:g}' for v in args.com or ())}: the centre of mass is within "
            f"{MAX_COM_DISTANCE:g} m of the sensor [m] (millimetres given?)",
        ),
        (
            args.mount_rpy_deg is not None and max(map(abs, args.mount_rpy_deg)) > 360.0,
            f"--mount-rpy-deg takes angles within ±360 [deg], got {args.mount_rpy_deg}",
        ),
    )
    truth = paper_like_truth()
    if args.tool_mass is not None or args.com is not None:
        truth = SensorModel.from_tool(
            tool_mass=args.tool_mass if args.tool_mass is not None else truth.tool_mass,
            center_of_mass=args.com if args.com is not None else truth.center_of_mass,
            force_offset=truth.force_offset,
            torque_offset=truth.torque_offset,
            base_tilt=truth.base_tilt,
        )
    mount = (  # R_M = Rz(Y) Ry(P) Rx(R)
        np.eye(3)
        if args.mount_rpy_deg is None
        else euler_zyx_to_matrix(np.deg2rad(args.mount_rpy_deg)[::-1])
    )
    paper = SensorNoise.paper()
    noise = SensorNoise(paper.force_std * args.noise_scale, paper.torque_std * args.noise_scale)
    drift = SensorDrift.typical() if args.with_drift else None
    return sim_inputs.SimulatedInputs(truth, noise, drift, mount, float(args.sensor_sign))


def _trajectory(args, arm):
    """``(t, q, dq, ddq)`` of ``--trajectory`` or of an excitation planned for ``--duration``."""
    if args.trajectory is None:
        from ..planning.excitation import plan_excitation

        plan = plan_excitation(arm, resolved(args.duration, 10.0), rate=1000.0, seed=args.seed)
        return plan.times, plan.joint_positions, plan.joint_velocities, plan.joint_accelerations
    table = read_table(args.trajectory)
    names = list(arm.joint_names)
    wanted = ["t", *names, *(f"{n}_vel" for n in names), *(f"{n}_acc" for n in names)]
    missing = [name for name in wanted if name not in table.header]
    if missing:
        raise InvalidInput(
            f"{args.trajectory}: expected the columns of ftkin plan --excitation, missing "
            f"{', '.join(missing)}"
        )
    values = table.floats(wanted)
    return (values[:, 0], *np.split(values[:, 1:], 3, axis=1))


def _signed(values) -> str:
    """``+0.1234, -0.5000, ...``: the truth's vectors as the command prints them."""
    return ", ".join(f"{x:+.4f}" for x in values)


def run_input(args) -> int:
    """``ftkin simulate samples|log|recording|bag``: write the example input, print the truth."""
    arm = arm_from_args(args) or Arm.default()
    rng = np.random.default_rng(args.seed)
    inputs = _inputs(args)
    truth = inputs.truth
    print(
        f"truth: tool {truth.tool_mass:.4f} kg, COM [{_signed(truth.center_of_mass)}] m, "
        f"F0 [{_signed(truth.force_offset)}] N, M0 [{_signed(truth.torque_offset)}] N·m, "
        f"tilt U, V {truth.base_tilt_deg[0]:+.3f}°, {truth.base_tilt_deg[1]:+.3f}°"
    )
    if args.kind in ("samples", "bag"):
        configurations = (
            arm.random_configurations(resolved(args.n, DEFAULT_POSES), rng, margin=0.3)
            if args.poses is None
            else configurations_from_table(read_table(args.poses), arm)
        )
    if args.kind == "bag":
        sim_inputs.write_bag(args.output, inputs, arm, configurations, rng)
        print(f"wrote {args.output}: a ROS 2 bag of {len(configurations)} poses held 2 s each")
        return 0
    if args.kind == "samples":
        readings = args.readings_per_pose
        header, rows = sim_inputs.samples_table(inputs, arm, configurations, rng, readings)
        what = f"{len(configurations)} poses × {readings} readings"
    elif args.kind == "log":
        header, rows = sim_inputs.log_table(inputs, arm, rng, resolved(args.duration, 5.0))
        what = f"{len(rows)} rows, a push {sim_inputs.PUSH.tolist()} (true_fx..true_mz)"
    else:
        from ..sim.mujoco.tool_inertia import ToolInertia

        tool = ToolInertia(truth.tool_mass, truth.center_of_mass, np.diag([2e-3, 2e-3, 1e-3]))
        times, q, dq, ddq = _trajectory(args, arm)
        try:
            header, rows = sim_inputs.recording_table(inputs, arm, times, q, dq, ddq, rng, tool)
        except InvalidInput as error:
            raise InvalidInput(
                f"ftkin simulate recording needs a URDF whose link 'gripper' is bolted to the "
                f"sensor (the bundled arm): {error}"
            ) from None
        what = f"{len(rows)} rows over {times[-1]:.1f} s, tool inertia diag(2e-3, 2e-3, 1e-3) kg·m²"
    write_csv(args.output, header, rows)
    print(f"wrote {args.output}: {what}")
    return 0
