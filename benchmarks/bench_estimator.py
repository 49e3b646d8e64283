"""Efficiency of the calibration estimators against the Cramér–Rao bound, and their speed.

Monte-Carlo on the bundled arm: one fixed set of N = 12 random poses (joint
limits shrunk by a margin, orientations from forward kinematics), a tool of
15 N with its centre of mass a few cm off the sensor axis, a base tilted by a
fraction of a degree, per-reading noise 0.03 N and 0.0015 N·m, several readings
per pose. The same poses are used in every trial (only the noise is redrawn),
so the Cramér–Rao bound is the single one computed from the Fisher
information at the truth for that pose set.

Estimators compared on the same data in each trial:

* ``linear``: the paper's two-step least squares;
* ``ml known``: maximum likelihood with the true noise levels given;
* ``ml spread``: noise estimated from the spread of the repeated readings;
* ``ml resid``: the readings of each pose averaged first, so no spread is
  available and the noise is estimated from the residuals.

For each parameter the table prints the CRLB standard deviation, each
estimator's RMS error and its efficiency ``CRLB² / RMSE²`` (target for ml:
≥ 0.9), and the ratio of ml's mean reported standard error to its RMS error.
Then the median time per fit for 12 poses and for 10,000 raw readings.

Run: ``python benchmarks/bench_estimator.py [--trials 1000] [--seed 0]``.
"""

from __future__ import annotations

import argparse
import logging
import time

import numpy as np

from ftkin import Arm, Samples, SensorModel, SensorNoise, SimulatedSensor, calibrate
from ftkin.calibration import fisher_information
from ftkin.calibration.information import (
    covariance_from_information,
    extended_parameters,
    extended_standard_errors,
)

POSES = 12
READINGS_PER_POSE = 10
MARGIN = 0.3  # [rad] kept from each joint limit
NOISE = SensorNoise(0.03, 0.0015)  # per reading [N], [N·m]
TRUTH = SensorModel.from_tool(
    tool_mass=15.0 / 9.80665,  # 15 N tool [kg]
    center_of_mass=[0.03, -0.02, 0.08],  # [m] sensor frame, a few cm off-axis
    force_offset=[2.0, -1.5, 3.0],  # [N]
    torque_offset=[0.10, -0.05, 0.02],  # [N·m]
    base_tilt=np.deg2rad([0.3, -0.2]),  # U, V [rad]
)
LABELS = [f"{block}[{axis}]" for block in ("a", "F0", "M0", "P") for axis in "xyz"] + [
    "G",
    "U",
    "V",
]
UNITS = ["N"] * 6 + ["N·m"] * 3 + ["m"] * 3 + ["N", "rad", "rad"]


def monte_carlo(trials: int, rng: np.random.Generator, arm: Arm):
    configurations = arm.random_configurations(POSES, rng, margin=MARGIN)
    rotations = arm.rotation_sensor_to_base(configurations)
    crlb = extended_standard_errors(
        TRUTH,
        covariance_from_information(fisher_information(TRUTH, rotations, NOISE, READINGS_PER_POSE)),
    )
    sensor = SimulatedSensor(TRUTH, NOISE)
    names = ("linear", "ml known", "ml spread", "ml resid")
    errors = {name: np.empty((trials, 15)) for name in names}
    reported = {name: np.empty((trials, 15)) for name in names[1:]}
    truth = extended_parameters(TRUTH)
    for trial in range(trials):
        samples = sensor.samples(rotations, rng, READINGS_PER_POSE)
        poses = samples.pose_averages()
        means = Samples(poses.wrenches, poses.rotations)
        results = {
            "linear": calibrate(samples, method="linear"),
            "ml known": calibrate(samples, noise=NOISE),
            "ml spread": calibrate(samples),
            "ml resid": calibrate(means),
        }
        for name, result in results.items():
            errors[name][trial] = extended_parameters(result) - truth
            if name in reported:
                reported[name][trial] = extended_standard_errors(result, result.covariance)
    return crlb, errors, reported


def median_time(function, repeats: int) -> float:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        function()
        times.append(time.perf_counter() - start)
    return float(np.median(times))


def timing(rng: np.random.Generator, arm: Arm) -> list[tuple[str, float]]:
    sensor = SimulatedSensor(TRUTH, NOISE)
    rows = []
    rotations = arm.rotation_sensor_to_base(arm.random_configurations(POSES, rng, margin=MARGIN))
    small = sensor.samples(rotations, rng, 1)
    small_repeated = sensor.samples(rotations, rng, READINGS_PER_POSE)
    rows.append(
        (
            "linear, 12 poses x 1 reading",
            median_time(lambda: calibrate(small, method="linear"), 200),
        )
    )
    rows.append(
        ("ml known noise, 12 poses x 1", median_time(lambda: calibrate(small, noise=NOISE), 200))
    )
    rows.append(("ml noise from residuals, 12 x 1", median_time(lambda: calibrate(small), 200)))
    rows.append(
        (
            f"ml noise from spread, 12 x {READINGS_PER_POSE}",
            median_time(lambda: calibrate(small_repeated), 200),
        )
    )
    many = arm.rotation_sensor_to_base(arm.random_configurations(400, rng, margin=MARGIN))
    big = sensor.samples(many, rng, 25)
    rows.append(("ml, 10,000 readings (400 poses x 25)", median_time(lambda: calibrate(big), 20)))
    rows.append(
        (
            "  Samples(...) validation of those",
            median_time(lambda: Samples(big.wrenches, big.rotations, big.pose_ids), 20),
        )
    )
    rows.append(
        (
            "ml + drop outliers, 10,000 readings",
            median_time(lambda: calibrate(big, drop_outliers=True), 20),
        )
    )
    return rows


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--trials", type=int, default=1000, help="Monte-Carlo trials (default: %(default)s)"
    )
    parser.add_argument("--seed", type=int, default=0, help="random seed (default: %(default)s)")
    args = parser.parse_args(argv)
    logging.getLogger("ftkin").setLevel(
        logging.ERROR
    )  # the rare flagged pose of a clean trial is expected
    rng = np.random.default_rng(args.seed)
    arm = Arm.default()
    start = time.perf_counter()
    crlb, errors, reported = monte_carlo(args.trials, rng, arm)
    elapsed = time.perf_counter() - start
    print(
        f"Monte-Carlo: {args.trials} trials, one fixed set of {POSES} poses, {READINGS_PER_POSE} "
        "readings per pose, "
        f"noise {NOISE.force_std[0]} N / {NOISE.torque_std[0]} N·m per reading, tool "
        f"{TRUTH.tool_weight:.1f} N "
        f"({elapsed:.1f} s)"
    )
    names = list(errors)
    header = f"{'param':<7}{'unit':<5}{'CRLB std':>10}" + "".join(
        f"{'RMSE ' + n:>16}" for n in names
    )
    header += "".join(f"{'eff ' + n:>15}" for n in names) + f"{'SE/RMSE spread':>16}"
    print(header)
    rmse = {name: np.sqrt(np.mean(errors[name] ** 2, axis=0)) for name in names}
    efficiency = {name: crlb**2 / rmse[name] ** 2 for name in names}
    se_ratio = np.mean(reported["ml spread"], axis=0) / rmse["ml spread"]
    for k, label in enumerate(LABELS):
        row = f"{label:<7}{UNITS[k]:<5}{crlb[k]:>10.3g}" + "".join(
            f"{rmse[n][k]:>16.3g}" for n in names
        )
        row += "".join(f"{efficiency[n][k]:>15.2f}" for n in names) + f"{se_ratio[k]:>16.2f}"
        print(row)
    print(
        "min efficiency: "
        + ", ".join(f"{n} {efficiency[n].min():.2f}" for n in names)
        + f"  (sampling error of an efficiency at {args.trials} trials ≈ "
        f"{np.sqrt(2 / args.trials):.0%})"
    )
    print()
    print(f"{'timing (median)':<42}{'ms per fit':>12}")
    for label, seconds in timing(rng, arm):
        print(f"{label:<42}{1e3 * seconds:>12.2f}")


if __name__ == "__main__":
    from _targets import run_benchmark

    raise SystemExit(run_benchmark(main))
