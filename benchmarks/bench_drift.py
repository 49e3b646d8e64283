"""A drifting bias: calibration with ``drift="none"`` against ``"auto"``, and online tracking.

Simulated on the bundled arm: a 15 N tool with its centre of mass a few cm off
the sensor axis, base tilted by a fraction of a degree, per-reading noise
0.03 N / 0.0015 N·m. The sensor is powered on at ``t = 0`` and drifts
(:meth:`ftkin.sim.SensorDrift.typical`): a warm-up of ±0.5 N / ±0.01 N·m per
channel with a 5-minute time constant plus a random walk of 0.002 N/√s
(4e-5 N·m/√s).

1. **Calibration.** 40 random poses over the first 20 minutes (one every
   30 s, 10 readings at 100 Hz each), new drift and noise in every trial,
   (a) in a random order and (b) the same poses in the order ftkin plans for
   a drifting sensor (:func:`ftkin.planning.drift_order.drift_robust_order`,
   ``ftkin plan --drift-rate``). RMS errors of mass, centre of mass and tilt
   with ``drift="none"`` and ``"auto"`` against the drift-free Cramér–Rao
   bound (the same poses with a constant bias), and beside it the bound with
   the random walk alone, its rate known (whitened by the Kalman filter): no
   estimator facing that walk can beat it, so it is the floor for ``auto``'s
   ratio; which model auto took; auto's mean reported standard error over its
   RMS error (honest standard errors are ≈ 1). RMS errors over 40 trials are
   themselves uncertain by about ±7 % (100 trials).
2. **5-fold cross-validation** (for each order;
   :func:`ftkin.calibration.cross_validate`, ``ftkin calibrate
   --cross-validate 5``). Poses split in 5 folds; each fold's pose means
   compensated with a calibration on the other four (auto: its bias at the
   pose's time); RMS of the compensated force [N] (truth: no contact).
3. **Control sessions** (5 by default, each with its own drift, script and
   noise; medians over the sessions, and the range of the ratio). 30 minutes after the calibration
   (t = 20..50 min),
   100 Hz: moves between poses (up to 0.5 rad/s), contact episodes (2–15 N,
   ramped in 0.3 s, 5–20 s long) and free still moments (2–8 s). The bias used by a
   :class:`ftkin.Compensator` with a fixed bias (the calibration's last) and
   with a :class:`ftkin.control.BiasTracker` (contact detected, or declared by the
   controller): RMS over the session of the compensated force error [N]
   without the sensor's white noise (compensated minus true contact force:
   bias error plus the calibration's tool-gravity error at each pose), and the
   number of tracker updates that used a reading taken during a contact
   (``BiasTracker.last_update_ticks``; target 0, the worst session shown). The
   oracle row is the same Kalman filter told exactly which ticks are still and
   free (the best a tracker can do with the reading noise). The
   last row is the floor with these free moments: the true bias at the last
   still, free tick, held through contacts and moves (the bias still wanders
   between free moments; it also counts the single repeated first sample of
   each move as a still, free moment known without noise). One session's
   ratio depends much on its walk (a fixed bias is as good as the walk is
   quiet): hence several sessions.

4. **Reading noise with one reading per pose** (``--noise-trials``, 200 by default): the same
   40 poses with a single reading each, a random-walk drift at the typical rate (no warm-up),
   ``drift="random-walk"`` with the noise estimated (neither given nor from repeated
   readings). The reported force and torque noise over the truth (mean, median and the share
   of trials within ±30 %), and the mean reported standard error over the RMS error of every
   quantity. A second row has a walk five times faster (the walk between poses larger than
   the noise of a reading): there the plain likelihood put the force noise at ~0 in most
   trials. Targets, each row: mean and median noise within ±30 % of the truth, SE÷RMSE
   within 0.8–1.25 (PASS/FAIL per row; the script exits with status 1 when one fails).

Run: ``python benchmarks/bench_drift.py [--trials 100] [--sessions 5] [--noise-trials 200]
[--seed 0] [--only-noise]`` (about 5 minutes; ``--only-noise`` about 1).
"""

from __future__ import annotations

import argparse
import logging
import time

import numpy as np

from ftkin import Arm, Compensator, SensorModel, SensorNoise, SimulatedSensor, calibrate
from ftkin.calibration import cross_validate, fisher_information
from ftkin.calibration.information import covariance_from_information, extended_standard_errors
from ftkin.calibration.random_walk import walk_gains, whiten
from ftkin.control import BiasTracker
from ftkin.planning.drift_order import drift_robust_order
from ftkin.planning.evaluation import expected_tool
from ftkin.sim import SensorDrift
from ftkin.sim.sensor import recording_times

POSES, READINGS, DURATION = 40, 10, 1200.0  # calibration: poses, readings per pose, length [s]
READING_INTERVAL = 0.01  # [s]
NOISE = SensorNoise(0.03, 0.0015)  # per reading [N], [N·m]
TRUTH = SensorModel.from_tool(
    tool_mass=15.0 / 9.80665,
    center_of_mass=[0.03, -0.02, 0.08],
    force_offset=[2.0, -1.5, 3.0],
    torque_offset=[0.10, -0.05, 0.02],
    base_tilt=np.deg2rad([0.3, -0.2]),
)
DRIFT = SensorDrift.typical()
SESSION, RATE = 1800.0, 100.0  # control session length [s] and rate [Hz]
TIP = np.array([0.0, 0.0, 0.12])  # contact point in the sensor frame [m]


def quantities(model) -> np.ndarray:
    """Mass [kg], COM x, y, z [m], tilt U, V [rad]."""
    return np.concatenate([[model.tool_mass], model.center_of_mass, model.base_tilt])


def quantity_errors(model, covariance) -> np.ndarray:
    sigma = extended_standard_errors(model, covariance)
    return np.concatenate([[sigma[12] / model.g], sigma[9:12], sigma[13:15]])


def calibration_trials(arm, rotations, configurations, trials, rng):
    sensor = SimulatedSensor(TRUTH, NOISE, DRIFT)
    times = recording_times(POSES, READINGS, DURATION, READING_INTERVAL)
    errors = {"none": [], "auto": []}
    reported, models, cv = [], [], {"none": [], "auto": []}
    for trial in range(trials):
        samples = sensor.samples_at_configurations(arm, configurations, rng, READINGS, times=times)
        for drift in ("none", "auto"):
            result = calibrate(samples, drift=drift)
            errors[drift].append(quantities(result) - quantities(TRUTH))
            if drift == "auto":
                reported.append(quantity_errors(result, result.covariance))
                models.append(result.drift.model)
        if trial < max(3, trials // 5):
            for drift, rms in cross_validate(
                samples, seed=int(rng.integers(2**31))
            ).force_rms.items():
                cv[drift].append(rms)
    return (
        errors,
        np.array(reported),
        models,
        {k: float(np.sqrt(np.mean(np.square(v)))) for k, v in cv.items()},
    )


def session_script(arm, rng):
    """Joint positions ``(T, nq)``, contact wrench ``(T, 6)`` and a 'declared free' flag per
    tick.
    """
    dt = 1.0 / RATE
    q_list, contact_list, free_list = [], [], []
    q = arm.random_configurations(1, rng, margin=0.4)[0]
    elapsed = 0.0
    while elapsed < SESSION:
        kind = rng.choice(["move", "still", "contact"], p=[0.35, 0.3, 0.35])
        if kind == "move":
            target = arm.random_configurations(1, rng, margin=0.4)[0]
            duration = max(np.max(np.abs(target - q)) / 0.5, 1.0)
            steps = int(duration * RATE)
            path = q + np.outer(np.linspace(0, 1, steps), target - q)
            q = target
            contact, free = np.zeros((steps, 6)), np.ones(steps, bool)
        else:
            steps = (
                int(rng.uniform(2, 8) * RATE) if kind == "still" else int(rng.uniform(5, 20) * RATE)
            )
            path = np.tile(q, (steps, 1))
            contact, free = np.zeros((steps, 6)), np.full(steps, kind == "still")
            if kind == "contact":
                direction = rng.standard_normal(3)
                force = rng.uniform(2, 15) * direction / np.linalg.norm(direction)
                ramp = int(0.3 * RATE)
                envelope = np.minimum(
                    1.0, np.minimum(np.arange(steps) + 1, steps - np.arange(steps)) / ramp
                )
                contact[:, :3] = envelope[:, None] * force
                contact[:, 3:] = envelope[:, None] * np.cross(TIP, force)
        q_list.append(path), contact_list.append(contact), free_list.append(free)
        elapsed += steps * dt
    return np.concatenate(q_list), np.concatenate(contact_list), np.concatenate(free_list)


def control_session(arm, configurations, rng):
    sensor = SimulatedSensor(TRUTH, NOISE, DRIFT)
    calibration_times = recording_times(POSES, READINGS, DURATION, READING_INTERVAL)
    q, contact, declared_free = session_script(arm, rng)
    session_times = DURATION + np.arange(len(q)) / RATE
    drift = sensor.bias_drift(np.concatenate([calibration_times, session_times]), rng)
    samples = sensor.samples_at_configurations(
        arm,
        configurations,
        rng,
        READINGS,
        times=calibration_times,
        bias_drift=drift[: len(calibration_times)],
    )
    calibration = calibrate(samples)
    true_bias = TRUTH.bias + drift[len(calibration_times) :]
    rotations = arm.rotation_sensor_to_base(q)
    raw = sensor.read(
        rotations, rng, contact_wrench=contact, bias_drift=drift[len(calibration_times) :]
    )
    # compensated minus true contact without the white noise = (true − used bias) + (true −
    # calibrated tool gravity)
    model_error = (
        TRUTH.tool_gravity_wrench(rotations) - calibration.tool_gravity_wrench(rotations)
    )[:, :3]
    rate = (
        calibration.drift.rate if calibration.drift.rate is not None else DRIFT.random_walk[[0, 3]]
    )
    still_free = declared_free & np.concatenate([[False], np.all(q[1:] == q[:-1], axis=1)])
    rows = {}
    for name, mode in (
        ("fixed bias", None),
        ("tracker (contact detected)", "detect"),
        ("tracker (free declared)", "declare"),
        ("oracle: tracker told still+free", "oracle"),
    ):
        tracker = None if mode is None else BiasTracker.from_calibration(calibration, rate=rate)
        compensator = Compensator(calibration, arm, tracker)
        flags = {"declare": declared_free, "oracle": still_free}.get(mode)
        used = np.empty((len(q), 6))
        used_readings = []
        dt = 1.0 / RATE
        start = time.process_time()
        for i in range(len(q)):
            used[i] = compensator._bias
            if tracker is None:
                compensator.compensate(q[i], raw[i])
                continue
            before = tracker.update_count
            measured = compensator.compensate(q[i], raw[i])  # `contact` is the session's truth
            compensator.observe_bias(
                measured, dt, q=q[i], free=None if flags is None else bool(flags[i])
            )
            if tracker.update_count != before:
                first, last = (
                    tracker.last_update_ticks
                )  # tracker ticks count from 1: tick i is session index i - 1
                used_readings.append((first - 1, last - 1))
        per_tick = (time.process_time() - start) / len(q)
        in_contact = np.any(contact != 0.0, axis=1)
        during_contact = sum(
            bool(np.any(in_contact[first : last + 1])) for first, last in used_readings
        )
        error = np.linalg.norm(true_bias[:, :3] - used[:, :3] + model_error, axis=1)
        rows[name] = (
            float(np.sqrt(np.mean(error**2))),
            float(np.max(error)),
            len(used_readings),
            during_contact,
            per_tick,
        )
    # floor: the true bias at the last still, free tick (what a perfect tracker with these free
    # moments could know)
    last = np.maximum.accumulate(np.where(still_free, np.arange(len(q)), 0))
    used = np.where((np.cumsum(still_free) > 0)[:, None], true_bias[last], calibration.bias)
    error = np.linalg.norm(true_bias[:, :3] - used[:, :3] + model_error, axis=1)
    rows["floor: true bias at free moments"] = (
        float(np.sqrt(np.mean(error**2))),
        float(np.max(error)),
        0,
        0,
        float("nan"),
    )
    return rows, calibration.drift.model, float(np.mean(np.any(contact != 0, axis=1))), len(q)


def walk_bound_ratio(rotations, crlb) -> np.ndarray:
    """The bound with the random walk alone (rate known), over the drift-free CRLB, for poses in
    this order.
    """
    pose_times = (
        recording_times(POSES, READINGS, DURATION, READING_INTERVAL)
        .reshape(POSES, READINGS)
        .mean(axis=1)
    )
    gains = walk_gains(
        pose_times, np.tile(NOISE.channel_std**2 / READINGS, (POSES, 1)), DRIFT.random_walk
    )
    whitened = whiten(gains, TRUTH.parameter_jacobian(rotations)).reshape(-1, 12)
    return quantity_errors(TRUTH, covariance_from_information(whitened.T @ whitened)) / crlb


def calibration_table(arm, configurations, trials, rng, title) -> float:
    rotations = arm.rotation_sensor_to_base(configurations)
    crlb = quantity_errors(
        TRUTH, covariance_from_information(fisher_information(TRUTH, rotations, NOISE, READINGS))
    )
    walk_bound = walk_bound_ratio(rotations, crlb)
    errors, reported, models, cv = calibration_trials(arm, rotations, configurations, trials, rng)
    labels = ["mass [kg]", "COM x [m]", "COM y [m]", "COM z [m]", "tilt U [rad]", "tilt V [rad]"]
    print(
        f"{title}: {POSES} poses over {DURATION / 60:.0f} min, {trials} trials "
        f"(auto chose: {', '.join(f'{m} ×{models.count(m)}' for m in sorted(set(models)))})"
    )
    print(
        f"{'quantity':<14}{'CRLB (no drift)':>16}{'none RMSE':>12}{'÷CRLB':>8}{'auto RMSE':>12}"
        f"{'÷CRLB':>8}"
        f"{'walk bound÷CRLB':>17}{'auto SE÷RMSE':>14}"
    )
    rmse = {k: np.sqrt(np.mean(np.square(v), axis=0)) for k, v in errors.items()}
    for i, label in enumerate(labels):
        print(
            f"{label:<14}{crlb[i]:>16.3g}{rmse['none'][i]:>12.3g}{rmse['none'][i] / crlb[i]:>8.2f}"
            f"{rmse['auto'][i]:>12.3g}{rmse['auto'][i] / crlb[i]:>8.2f}{walk_bound[i]:>17.2f}"
            f"{np.mean(reported[:, i]) / rmse['auto'][i]:>14.2f}"
        )
    print(
        f"5-fold cross-validated compensated force RMS [N]: none {cv['none']:.4f}, auto "
        f"{cv['auto']:.4f} "
        f"(none/auto = {cv['none'] / cv['auto']:.1f}x)\n"
    )
    return cv["none"] / cv["auto"]


NOISE_TARGET, SE_TARGET = 0.3, (0.8, 1.25)  # section 4: |mean noise / truth − 1|, SE÷RMSE range


def noise_trials(arm, configurations, trials, rate, rng):
    """Reported noise over the truth ``(T, 2)``, errors and standard errors ``(T, 6)``, models."""
    sensor = SimulatedSensor(TRUTH, NOISE, SensorDrift(random_walk=rate))
    times = recording_times(POSES, 1, DURATION, READING_INTERVAL)
    ratios, errors, reported, models = [], [], [], []
    for _ in range(trials):
        samples = sensor.samples_at_configurations(arm, configurations, rng, 1, times=times)
        result = calibrate(samples, drift="random-walk")
        ratios.append(result.diagnostics.noise.channel_std[[0, 3]] / NOISE.channel_std[[0, 3]])
        errors.append(quantities(result) - quantities(TRUTH))
        reported.append(quantity_errors(result, result.covariance))
        models.append(result.drift.model)
    return np.array(ratios), np.array(errors), np.array(reported), models


def noise_table(arm, configurations, trials, rng) -> bool:
    """Section 4; True when every target is met."""
    print(
        f"4. Reading noise, one reading per pose: {POSES} poses over {DURATION / 60:.0f} min, "
        f"{trials} trials, drift='random-walk', noise estimated (truth {NOISE.channel_std[0]} N, "
        f"{NOISE.channel_std[3]} N·m per reading)"
    )
    labels = ["mass", "COM x", "COM y", "COM z", "tilt U", "tilt V"]
    print(
        f"{'walk [N/√s, N·m/√s]':<22}{'noise÷truth F':>14}{'T':>6}{'median F':>9}{'T':>6}"
        f"{'±30 % F':>8}{'T':>6}  SE÷RMSE {' '.join(f'{label:>6}' for label in labels)}"
        f"{'fallbacks':>10}  target"
    )
    passed = True
    for rate in (DRIFT.random_walk[[0, 3]], 5 * DRIFT.random_walk[[0, 3]]):
        ratios, errors, reported, models = noise_trials(arm, configurations, trials, rate, rng)
        se_rmse = np.mean(reported, axis=0) / np.sqrt(np.mean(errors**2, axis=0))
        mean, median = np.mean(ratios, axis=0), np.median(ratios, axis=0)
        within = np.mean(np.abs(ratios - 1.0) <= NOISE_TARGET, axis=0)
        ok = bool(
            np.all(np.abs(np.concatenate([mean, median]) - 1.0) <= NOISE_TARGET)
            and np.all((se_rmse >= SE_TARGET[0]) & (se_rmse <= SE_TARGET[1]))
        )
        passed &= ok
        fallbacks = sum(model != "random-walk" for model in models)
        print(
            f"{f'{rate[0]:g}, {rate[1]:g}':<22}{mean[0]:>14.2f}{mean[1]:>6.2f}{median[0]:>9.2f}"
            f"{median[1]:>6.2f}{100 * within[0]:>7.0f}%{100 * within[1]:>5.0f}%          "
            f"{' '.join(f'{value:>6.2f}' for value in se_rmse)}{fallbacks:>10}  "
            f"{'PASS' if ok else 'FAIL'}"
        )
    print(
        f"targets: mean and median noise within ±{100 * NOISE_TARGET:.0f} % of the truth, SE÷RMSE "
        "within "
        f"{SE_TARGET[0]}–{SE_TARGET[1]}\n"
    )
    return passed


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=100)
    parser.add_argument("--sessions", type=int, default=5)
    parser.add_argument("--noise-trials", type=int, default=200)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--only-noise", action="store_true", help="run section 4 alone")
    args = parser.parse_args(argv)
    logging.getLogger("ftkin").setLevel(logging.ERROR)
    rng = np.random.default_rng(args.seed)
    arm = Arm.default()
    configurations = arm.random_configurations(POSES, rng, margin=0.3)
    start = time.perf_counter()
    noise_rng = np.random.default_rng([args.seed, 4])  # section 4 draws apart from the others
    if args.only_noise:
        return 0 if noise_table(arm, configurations, args.noise_trials, noise_rng) else 1
    calibration_table(
        arm, configurations, args.trials, rng, "1a. Calibration, random poses in a random order"
    )
    order, _ = drift_robust_order(
        expected_tool(TRUTH.tool_weight, TRUTH.center_of_mass),
        arm.rotation_sensor_to_base(configurations),
        rate=DRIFT.random_walk,
        noise_std=NOISE.channel_std,
        readings_per_pose=READINGS,
        pose_interval=DURATION / POSES,
        rng=np.random.default_rng(args.seed),
    )
    calibration_table(
        arm,
        configurations[order],
        args.trials,
        rng,
        "1b. Calibration, the same poses in ftkin's drift-robust order (plan --drift-rate)",
    )
    sessions = [
        control_session(arm, configurations, np.random.default_rng([args.seed, k]))
        for k in range(args.sessions)
    ]
    print(
        f"3. Control sessions: {args.sessions} × {SESSION / 60:.0f} min at {RATE:.0f} Hz "
        f"({sessions[0][3]} ticks each, {100 * np.mean([s[2] for s in sessions]):.0f} % in "
        "contact), "
        f"calibration drift models {sorted(set(s[1] for s in sessions))}; medians over the sessions"
    )
    print(
        f"{'bias used':<34}{'error RMS [N]':>14}{'max [N]':>10}{'updates':>9}{'in contact':>12}"
        f"{'µs/tick':>9}"
        f"{'fixed÷this':>12}{'(min–max)':>14}"
    )
    for name in sessions[0][0]:
        values = np.array([s[0][name] for s in sessions])
        ratios = np.array([s[0]["fixed bias"][0] / s[0][name][0] for s in sessions])
        rms, worst, updates, _, per_tick = np.median(values, axis=0)
        during = int(np.max(values[:, 3]))  # the worst session: target 0
        updates_text = (
            f"{updates:>9.0f}{during:>12d}{per_tick * 1e6:>9.1f}"
            if np.isfinite(per_tick)
            else f"{'-':>9}{'-':>12}{'-':>9}"
        )
        ratio_text = (
            ""
            if name == "fixed bias"
            else f"{np.median(ratios):>11.1f}x{f'({ratios.min():.1f}–{ratios.max():.1f})':>14}"
        )
        print(f"{name:<34}{rms:>14.4f}{worst:>10.4f}{updates_text}{ratio_text}")
    print()
    noise_ok = noise_table(arm, configurations, args.noise_trials, noise_rng)
    print(f"(total {time.perf_counter() - start:.0f} s)")
    return 0 if noise_ok else 1


if __name__ == "__main__":
    from _targets import run_benchmark

    raise SystemExit(run_benchmark(main))
