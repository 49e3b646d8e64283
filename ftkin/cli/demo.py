"""``ftkin demo``: calibrate and compensate a simulated sensor on the bundled arm.

With the ``sim`` extra (MuJoCo) installed, the demo ends with a short closed
loop: the arm places an object on the book in MuJoCo at 1 kHz, admittance
control compensated with the calibration just estimated (``--sim-seconds 0``
skips it).
"""

import importlib.util

import numpy as np

from .. import Arm, Compensator, SensorNoise, calibrate, save_calibration
from ..sim.sensor import SimulatedSensor, paper_like_truth
from .arg_types import add_command, non_negative_float, option
from .pose_options import add_readings_argument
from .shared_options import DEFAULT_POSES, METHOD, POSES, SEED, resolved


def register(subparsers) -> None:
    add_command(
        subparsers,
        "demo",
        help="simulated sensor on the bundled arm: calibrate, compare with the truth, compensate",
        options=(
            POSES,
            SEED,
            METHOD,
            option("-o", "--output", metavar="CALIB.json", help="also write the calibration file"),
            option(
                "--sim-seconds",
                type=non_negative_float,
                default=2.0,
                metavar="S",
                help="simulated seconds of the closed-loop MuJoCo segment (needs the 'sim' extra; "
                "0 skips it; default: %(default)s)",
            ),
        ),
        groups=(add_readings_argument,),
        run=run,
    )


def _row(name: str, unit: str, truth, estimate, decimals: int, std_error=None) -> str:
    truth, estimate = np.atleast_1d(truth), np.atleast_1d(estimate)
    fmt = lambda v: "[" + ", ".join(f"{x:+.{decimals}f}" for x in v) + "]"  # noqa: E731
    error = np.abs(estimate - truth)
    ratio = "" if std_error is None else f"{np.max(error / np.atleast_1d(std_error)):.1f}"
    return f"  {name:<16}{fmt(truth):<36}{fmt(estimate):<36}{error.max():.1e} {unit:<5}{ratio}"


def run(args) -> int:
    rng = np.random.default_rng(args.seed)
    args.n = resolved(args.n, DEFAULT_POSES)
    arm = Arm.default()
    truth = paper_like_truth()
    sensor = SimulatedSensor(truth, SensorNoise.paper())
    samples = sensor.samples_at_configurations(
        arm,
        arm.random_configurations(args.n, rng, margin=0.3),
        rng,
        readings_per_pose=args.readings_per_pose,
    )
    print(
        f"Bundled arm {arm.urdf_path.name}, sensor frame {arm.sensor_frame}; {args.n} random "
        f"poses, {args.readings_per_pose} readings each, noise 0.02 N / 0.002 N·m per reading "
        f"(seed {args.seed})."
    )
    result = calibrate(samples, method=resolved(args.method, "ml"))
    print(result.summary())
    errors = result.std_errors or {}
    print(
        f"\n  {'parameter':<16}{'truth':<36}{'estimate':<36}{'max |error|':<14}max |error| / std "
        "error"
    )
    for name, unit, true_value, estimate, decimals in (
        ("force_offset", "N", truth.force_offset, result.force_offset, 4),
        ("torque_offset", "N·m", truth.torque_offset, result.torque_offset, 5),
        ("center_of_mass", "m", truth.center_of_mass, result.center_of_mass, 5),
        ("gravity_in_base", "N", truth.gravity_in_base, result.gravity_in_base, 4),
    ):
        print(_row(name, unit, true_value, estimate, decimals, errors.get(name)))
    tilt_error = np.rad2deg(errors["base_tilt"]) if "base_tilt" in errors else None
    print(_row("base_tilt_deg", "deg", truth.base_tilt_deg, result.base_tilt_deg, 3, tilt_error))

    contact = np.array(
        [1.5, -0.8, -4.0, 0.05, 0.02, -0.01]
    )  # N, N·m: the environment pushing on the tool
    q_check = arm.random_configurations(1, rng, margin=0.3)[0]
    raw = sensor.read(arm.rotation_sensor_to_base(q_check), rng, contact)[0]
    recovered = Compensator(result, arm).compensate(q_check, raw)
    print("\nCompensation at a new pose with a known contact wrench [N, N·m]:")
    for label, values in (("injected", contact), ("recovered", recovered), ("raw", raw)):
        print(f"  {label:<10}" + " ".join(f"{v:+.4f}" for v in values))
    print(
        f"  max error {np.max(np.abs(recovered - contact)):.4f} (noise of one reading: 0.02 N, "
        "0.002 N·m)"
    )
    if args.output:
        save_calibration(result, args.output)
        print(f"wrote {args.output}")
    if args.sim_seconds > 0 and importlib.util.find_spec("mujoco") is not None:
        _closed_loop(arm, result, args.sim_seconds, args.seed)
    return 0


def _closed_loop(arm: Arm, calibration, seconds: float, seed: int) -> None:
    """Place the paper's object on the book in MuJoCo, compensating with ``calibration``."""
    from ..sim.mujoco.mujoco_placement import simulate_placement_mujoco
    from ..sim.placement import PlacementScenario, admittance_controller
    from ..sim.surfaces import BOOK

    scenario = PlacementScenario(surface=BOOK, duration=seconds, seed=seed)
    run, _ = simulate_placement_mujoco(
        scenario, arm, controller=admittance_controller(scenario, arm, calibration)
    )
    placed = (
        f"placed at t = {run.settle_time:.2f} s"
        if np.isfinite(run.settle_time)
        else "not placed yet (run longer: --sim-seconds)"
    )
    print(
        f"\nClosed loop in MuJoCo ({seconds:g} s at 1 kHz): admittance with this calibration "
        f"lowers a {scenario.object_weight:.2f} N object onto the book:\n"
        f"  peak contact force {run.peak_contact_force:.2f} N, final F'z {run.final_force:+.3f} N, "
        f"{placed}\n"
        "  (ftkin simulate placement --mode all --plot run.png compares it with position control)"
    )
