"""``ftkin simulate samples|log|recording|bag``: example inputs from the simulated sensor.

Each writes a file the matching command reads, from known parameters
(:mod:`ftkin.sim.inputs`): the paper-like tool and bias
(:func:`~ftkin.sim.sensor.paper_like_truth`) unless ``--tool-mass``/``--com``
say otherwise, the paper's noise times ``--noise-scale``, and optionally a
drifting bias, a mount rotation on the flange or a reversed sign. The truth is
printed, so what ``ftkin calibrate`` finds can be compared with it.
"""

from __future__ import annotations

import numpy as np

from ..exceptions import InvalidInput
from .arg_types import bounded_int, number_list, positive_float, seed
from .common import add_arm_arguments, arm_from_args

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


def add_input_parsers(experiments) -> None:
    """Register ``samples``, ``log``, ``recording`` and ``bag`` under ``ftkin simulate``."""
    for kind, text in KINDS.items():
        parser = experiments.add_parser(kind, help=text, description=f"Write {text}.")
        _add_sensor_arguments(parser)
        add_arm_arguments(parser)
        if kind in ("samples", "bag"):
            parser.add_argument(
                "--poses",
                metavar="POSES.csv",
                help="joint configurations (ftkin plan -o POSES.csv; default: --n random ones)",
            )
            parser.add_argument(
                "--n",
                type=bounded_int(3, 1000, "poses"),
                default=12,
                help="random poses without --poses (default: %(default)s)",
            )
        if kind == "samples":
            parser.add_argument(
                "--readings",
                type=bounded_int(1, 100_000, "readings per pose"),
                default=10,
                help="readings per pose, 1 ms apart (default: %(default)s)",
            )
        if kind in ("log", "recording"):
            parser.add_argument(
                "--duration",
                type=positive_float,
                default=5.0 if kind == "log" else 10.0,
                metavar="S",
                help="length [s] (default: %(default)s)",
            )
        if kind == "recording":
            parser.add_argument(
                "--trajectory",
                metavar="TRAJ.csv",
                help="excitation to follow (ftkin plan --excitation -o TRAJ.csv; default: one "
                "planned for --duration)",
            )
        parser.add_argument("-o", "--output", required=True, metavar="FILE", help="file to write")
        parser.set_defaults(func=run, kind=kind)


def _add_sensor_arguments(parser) -> None:
    group = parser.add_argument_group("the simulated sensor and tool")
    group.add_argument("--seed", type=seed, default=0, help="random seed (default: %(default)s)")
    group.add_argument("--tool-mass", type=positive_float, metavar="KG", help="tool mass [kg]")
    group.add_argument(
        "--com", type=number_list, metavar="X Y Z", help="tool centre of mass, sensor frame [m]"
    )
    group.add_argument(
        "--noise-scale",
        type=positive_float,
        default=1.0,
        metavar="K",
        help="noise = K × the paper's 0.02 N, 0.002 N·m per reading (default: %(default)g)",
    )
    group.add_argument(
        "--drift",
        action="store_true",
        help="a drifting bias (warm-up and random walk, SensorDrift.typical()); samples get a t "
        "column",
    )
    group.add_argument(
        "--mount-rpy-deg",
        type=number_list,
        metavar="R P Y",
        help="the sensor turned on the flange: R_M = Rz(Y) Ry(P) Rx(R) [deg]",
    )
    group.add_argument(
        "--sensor-sign",
        type=int,
        choices=(1, -1),
        default=1,
        help="-1: the sensor reports the reaction (default: %(default)s)",
    )


def _inputs(args):
    from ..calibration.information import SensorNoise
    from ..calibration.model import SensorModel
    from ..kinematics.rotations import euler_zyx_to_matrix
    from ..sim.inputs import SimulatedInputs
    from ..sim.sensor import paper_like_truth
    from ..sim.sensor_drift import SensorDrift

    truth = paper_like_truth()
    if args.tool_mass is not None or args.com is not None:
        if args.com is not None and len(args.com) != 3:
            raise InvalidInput(f"--com takes X Y Z [m], got {len(args.com)} numbers")
        truth = SensorModel.from_tool(
            tool_mass=args.tool_mass if args.tool_mass is not None else truth.tool_mass,
            center_of_mass=args.com if args.com is not None else truth.center_of_mass,
            force_offset=truth.force_offset,
            torque_offset=truth.torque_offset,
            base_tilt=truth.base_tilt,
        )
    mount = np.eye(3)
    if args.mount_rpy_deg is not None:
        if len(args.mount_rpy_deg) != 3:
            raise InvalidInput(f"--mount-rpy-deg takes R P Y [deg], got {args.mount_rpy_deg}")
        roll, pitch, yaw = np.deg2rad(args.mount_rpy_deg)
        mount = euler_zyx_to_matrix([yaw, pitch, roll])
    paper = SensorNoise.paper()
    noise = SensorNoise(paper.force_std * args.noise_scale, paper.torque_std * args.noise_scale)
    drift = SensorDrift.typical() if args.drift else None
    return SimulatedInputs(truth, noise, drift, mount, float(args.sensor_sign))


def _configurations(args, arm, rng) -> np.ndarray:
    if args.poses is None:
        return arm.random_configurations(args.n, rng, margin=0.3)
    from ..io.csv_table import read_table
    from ..sim.inputs import configurations_from_table

    return configurations_from_table(read_table(args.poses), arm)


def _trajectory(args, arm):
    """``(t, q, dq, ddq)`` of ``--trajectory`` or of an excitation planned for ``--duration``."""
    if args.trajectory is None:
        from ..planning.excitation import plan_excitation

        plan = plan_excitation(arm, args.duration, rate=1000.0, seed=args.seed)
        return plan.times, plan.joint_positions, plan.joint_velocities, plan.joint_accelerations
    from ..io.csv_table import read_table

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
    nq = len(names)
    return (
        values[:, 0],
        values[:, 1 : 1 + nq],
        values[:, 1 + nq : 1 + 2 * nq],
        values[:, 1 + 2 * nq :],
    )


def _print_truth(inputs) -> None:
    truth = inputs.truth
    numbers = lambda v: ", ".join(f"{x:+.4f}" for x in v)  # noqa: E731
    print(
        f"truth: tool {truth.tool_mass:.4f} kg, COM [{numbers(truth.center_of_mass)}] m, "
        f"F0 [{numbers(truth.force_offset)}] N, M0 [{numbers(truth.torque_offset)}] N·m, "
        f"tilt U, V {truth.base_tilt_deg[0]:+.3f}°, {truth.base_tilt_deg[1]:+.3f}°"
    )


def run(args) -> int:
    from ..io.csv_table import write_csv
    from ..kinematics.arm import Arm
    from ..sim import inputs as sim_inputs

    arm = arm_from_args(args) or Arm.default()
    rng = np.random.default_rng(args.seed)
    inputs = _inputs(args)
    _print_truth(inputs)
    if args.kind == "bag":
        configurations = _configurations(args, arm, rng)
        sim_inputs.write_bag(args.output, inputs, arm, configurations, rng)
        print(f"wrote {args.output}: a ROS 2 bag of {len(configurations)} poses held 2 s each")
        return 0
    if args.kind == "samples":
        configurations = _configurations(args, arm, rng)
        header, rows = sim_inputs.samples_table(inputs, arm, configurations, rng, args.readings)
        what = f"{len(configurations)} poses × {args.readings} readings"
    elif args.kind == "log":
        header, rows = sim_inputs.log_table(inputs, arm, rng, args.duration)
        what = f"{len(rows)} rows, a push {sim_inputs.PUSH.tolist()} (true_fx..true_mz)"
    else:
        from ..sim.mujoco.tool_inertia import ToolInertia

        tool = ToolInertia(
            inputs.truth.tool_mass, inputs.truth.center_of_mass, np.diag([2e-3, 2e-3, 1e-3])
        )
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
