"""The load in the hand beside Bota's payload estimator (issue 39), on one MuJoCo recording.

Setup: the bundled arm in MuJoCo (``ftkin.sim.mujoco.load_recording``) with MuJoCo's own
accelerometer and gyro at the sensor origin, sensor axes (specific force, +9.81 m/s² up at rest).
The gripper holds a 0.3245 kg load (its COM at (0.012, −0.006, 0.07) m, sensor frame) from t = 0
while the wrist turns about joints 4, 5 and 6 (cosine sweeps of 0.6 rad, periods 4, 3 and 5 s)
for 6 s at 1 kHz. Both estimators are given the load's wrench alone (MuJoCo's readings with the
load minus the same motion without it: the contact after the tool, as ftkin's compensation gives
it) with seeded white noise 0.02 N / 0.002 N·m, and the IMU's readings with noise 0.02 m/s² /
0.002 rad/s:

* ftkin: :class:`~ftkin.control.load_estimator.LoadEstimator`, each reading through
  ``add_motion`` (the sensor frame's velocity and acceleration from the joints, Pinocchio);
* Bota: ``bota_payload_utils.BotaPayloadEstimator`` 1.0.3 (closed C++, from the wrench and IMU
  readings), started at t = 0, its noise covariances given permuted as 1.0.3 reads them and its
  convergence thresholds set large so that it uses every reading (TOOLING.md "Bota Payload
  Utils"); it reports only at its end, so it is run once per length of data.

Rows: the mass error [%] and the COM error [mm] after 1 s and after 5 s of data, and the time to
converge: the first length of data (0.25 s steps) from which the error stays within 1 % and
2 mm. Bota's at 0.5, 1, 2, 3, 4, 5, 6 s of data only (one run each, 1 s + twice the data's length of
wall clock).
Skipped, with the reason, when ``bota-payload-utils`` is not installed.

Run: ``.venv/bin/python benchmarks/bench_load_bota.py``
"""

from __future__ import annotations

import contextlib
import json
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from ftkin import Arm
from ftkin.calibration.information import SensorNoise
from ftkin.calibration.regressor import sensor_motion
from ftkin.control.load_estimator import LoadEstimator
from ftkin.sim.mujoco.load_recording import MujocoLoadRecorder

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from _targets import verdict  # noqa: E402

RATE = 1000.0  # [Hz]
DURATION = 6.0  # [s]
MASS = 0.3245  # [kg]
COM = (0.012, -0.006, 0.07)  # [m, sensor frame]
NOISE = SensorNoise(0.02, 0.002)  # [N, N·m]
IMU_NOISE = (0.02, 0.002)  # [m/s², rad/s]
START = np.array([0.0, -0.6, 1.2, 0.0, 0.8, 0.0])  # [rad]
SWEEPS = ((3, 0.6, 4.0), (4, 0.6, 3.0), (5, 0.6, 5.0))  # (joint, amplitude [rad], period [s])
BOTA_LENGTHS = (0.5, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0)  # [s] of data per Bota run
MASS_TOLERANCE, COM_TOLERANCE = 0.01, 0.002  # converged: 1 %, 2 mm


class LoadImuRecorder(MujocoLoadRecorder):
    """The load recorder with MuJoCo's accelerometer and gyro at the sensor origin."""

    def _add_sensors(self, mujoco, spec, body) -> None:
        super()._add_sensors(mujoco, spec, body)
        body.add_site(name="bench_imu_site", pos=[0.0, 0.0, 0.0])
        for name, kind in (
            ("bench_accelerometer", mujoco.mjtSensor.mjSENS_ACCELEROMETER),
            ("bench_gyro", mujoco.mjtSensor.mjSENS_GYRO),
        ):
            spec.add_sensor(
                name=name, type=kind, objtype=mujoco.mjtObj.mjOBJ_SITE, objname="bench_imu_site"
            )

    def record(self, q, dq, ddq, mass: float):
        """``(wrench (N, 6), specific force (N, 3), gyro (N, 3))`` with the load of ``mass``."""
        mujoco, model, data = self._mujoco, self.model, self.data
        self.set_load_mass(mass)
        out = np.empty((len(q), 12))
        for i in range(len(q)):
            data.qpos[self._qpos], data.qvel[self._dof], data.qacc[self._dof] = q[i], dq[i], ddq[i]
            mujoco.mj_inverse(model, data)
            out[i] = data.sensordata[:12]
        return -out[:, :6], out[:, 6:9].copy(), out[:, 9:12].copy()


def recording():
    """``(t, q, dq, ddq, load wrench, specific force, gyro, true COM)``, noise included."""
    t = np.arange(int(DURATION * RATE)) / RATE
    q, dq, ddq = np.tile(START, (len(t), 1)), np.zeros((len(t), 6)), np.zeros((len(t), 6))
    for joint, amplitude, period in SWEEPS:
        w = 2 * np.pi / period
        q[:, joint] += amplitude * (1 - np.cos(w * t))
        dq[:, joint] = amplitude * w * np.sin(w * t)
        ddq[:, joint] = amplitude * w**2 * np.cos(w * t)
    recorder = LoadImuRecorder(load_position=COM)
    loaded, specific_force, gyro = recorder.record(q, dq, ddq, MASS)
    empty, _, _ = recorder.record(q, dq, ddq, 0.0)
    _, true_com = recorder.true_load(q[0])
    rng = np.random.default_rng(0)
    wrench = loaded - empty + rng.normal(size=(len(t), 6)) * NOISE.channel_std
    specific_force = specific_force + rng.normal(size=(len(t), 3)) * IMU_NOISE[0]
    gyro = gyro + rng.normal(size=(len(t), 3)) * IMU_NOISE[1]
    return t, q, dq, ddq, wrench, specific_force, gyro, true_com


def seconds(value: float) -> str:
    """A convergence time [s], or ``> 6`` when it did not converge within the recording."""
    return f"{value:.2f}" if np.isfinite(value) else f"> {DURATION:g}"


def errors(mass: float, com, true_com) -> tuple[float, float]:
    """``(mass error [%], COM error [mm])``."""
    return abs(mass / MASS - 1) * 100, float(np.linalg.norm(np.asarray(com) - true_com)) * 1e3


def converged_from(lengths, mass_errors, com_errors) -> float:
    """The first length from which every later error is within the tolerances (inf: never)."""
    ok = (np.asarray(mass_errors) <= MASS_TOLERANCE * 100) & (
        np.asarray(com_errors) <= COM_TOLERANCE * 1e3
    )
    for i in range(len(ok)):
        if ok[i:].all():
            return float(lengths[i])
    return float("inf")


def ftkin_run(t, q, dq, ddq, wrench, true_com):
    """ftkin's errors at every 0.25 s of data."""
    arm = Arm.default()
    rotations, velocities, accelerations = sensor_motion(arm, q, dq, ddq)
    estimator = LoadEstimator(NOISE, [0.0, 0.0, -9.80665])
    marks = {round(length * RATE): length for length in np.arange(0.25, DURATION + 1e-9, 0.25)}
    found = {}
    for i in range(len(t)):
        estimator.add_motion(rotations[i], velocities[i], accelerations[i], wrench[i])
        if i + 1 in marks:
            estimate = estimator.estimate()
            found[marks[i + 1]] = errors(estimate.mass, estimate.com_in_sensor, true_com)
    return found


def bota_config(folder: Path, min_time: float) -> Path:
    """Bota's estimator configuration (its 1.0.3 permutation of the noise covariances)."""
    force, torque = (float(v) ** 2 for v in (NOISE.force_std[0], NOISE.torque_std[0]))
    accel, gyro = IMU_NOISE[0] ** 2, IMU_NOISE[1] ** 2
    xyz = lambda v: {"x": v, "y": v, "z": v}  # noqa: E731
    config = {
        "payload_estimator_config": {
            "output_config_file_name": str(folder / "bota_out.json"),
            "min_time": min_time,
            "max_time": min_time + 60.0,
            "output_bias_estimate": False,
            "prior_payload_properties": {
                "mass": 0.0,
                "com": xyz(0.0),
                "inertia": {k: 0.0 for k in ("Ixx", "Iyy", "Izz", "Ixy", "Ixz", "Iyz")},
            },
            # 1.0.3 reads linear_acc as the force's, angular_vel as the torque's, angular_acc as
            # the linear acceleration's, force as the angular velocity's, torque as the angular
            # acceleration's (TOOLING.md)
            "measurement_noise_covariance": {
                "linear_acc": xyz(force),
                "angular_vel": xyz(torque),
                "angular_acc": xyz(accel),
                "force": xyz(gyro),
                "torque": xyz(1.0),
            },
            "estimation_covariance_convergence_threshold": {
                "mass": 1e9,
                "com": 1e9,
                "inertia": 1e9,
                "wrench_bias": 1e9,
            },
        }
    }
    path = folder / "bota_config.json"
    path.write_text(json.dumps(config))
    return path


@contextlib.contextmanager
def quiet_stdout():
    """Bota's C++ prints its log to the process's stdout: sent to /dev/null meanwhile."""
    sys.stdout.flush()
    saved = os.dup(1)
    with open(os.devnull, "w") as null:
        os.dup2(null.fileno(), 1)
        try:
            yield
        finally:
            os.dup2(saved, 1)
            os.close(saved)


def bota_run(bp, t, wrench, specific_force, gyro, length: float):
    """Bota's ``(mass, com)`` after ``length`` [s] of data, or None when it does not succeed."""
    with quiet_stdout():
        return _bota_run(bp, t, wrench, specific_force, gyro, length)


def _bota_run(bp, t, wrench, specific_force, gyro, length: float):
    count = int(round(length * RATE))
    rows = np.column_stack([wrench, specific_force, gyro])[:count]
    with tempfile.TemporaryDirectory() as name:
        folder = Path(name)
        # wall clock [s] since start, longer than feeding the rows takes (about 0.5 ms a row on a
        # loaded machine; checked below)
        min_time = 1.0 + 2.0 * length
        estimator = bp.BotaPayloadEstimator(str(bota_config(folder, min_time)))
        start = time.monotonic()
        estimator.start_payload_estimation()
        for i in range(count - 1):
            estimator.update(float(t[i]), np.ascontiguousarray(rows[i]))
        fed = time.monotonic() - start
        if fed >= min_time:
            raise RuntimeError(f"feeding {count} rows took {fed:.2f} s > min_time {min_time} s")
        time.sleep(min_time - fed + 0.05)
        estimator.update(float(t[count - 1]), np.ascontiguousarray(rows[count - 1]))
        deadline = time.monotonic() + 5.0
        while estimator.is_estimator_running() and time.monotonic() < deadline:
            time.sleep(0.01)
        out = folder / "bota_out.json"
        if not estimator.is_estimation_successful() or not out.is_file():
            return None
        found = json.loads(out.read_text())["payload_compensator_config"]["payload_properties"]
        com = found["com"]
        return float(found["mass"]), [com["x"], com["y"], com["z"]]


def main() -> None:
    t, q, dq, ddq, wrench, specific_force, gyro, true_com = recording()
    print(
        f"load {MASS} kg at {np.round(true_com, 4).tolist()} m (sensor frame), {DURATION:g} s of "
        f"wrist sweeps at {RATE:g} Hz, noise {NOISE.force_std[0]} N / {NOISE.torque_std[0]} N·m"
    )
    mine = ftkin_run(t, q, dq, ddq, wrench, true_com)
    lengths = sorted(mine)
    converged = converged_from(lengths, *zip(*(mine[length] for length in lengths)))
    print(
        f"{'':<7}{'mass err % 1 s':>15}{'COM mm 1 s':>11}{'mass err % 5 s':>15}"
        f"{'COM mm 5 s':>11}{'converged s':>12}"
    )
    print(
        f"{'ftkin':<7}{mine[1.0][0]:>15.3f}{mine[1.0][1]:>11.3f}{mine[5.0][0]:>15.3f}"
        f"{mine[5.0][1]:>11.3f}{seconds(converged):>12}  "
        f"{verdict(mine[5.0][0] <= 1.0 and mine[5.0][1] <= 2.0)}"
    )
    try:
        import bota_payload_utils as bp
    except ImportError:
        print(
            "bota: skipped, bota-payload-utils is not installed (pip install -e '.[bota-payload]')"
        )
        return
    theirs = {}
    for length in BOTA_LENGTHS:
        found = bota_run(bp, t, wrench, specific_force, gyro, length)
        theirs[length] = (float("nan"),) * 2 if found is None else errors(*found, true_com)
    lengths = sorted(theirs)
    converged = converged_from(lengths, *zip(*(theirs[length] for length in lengths)))
    print(
        f"{'bota':<7}{theirs[1.0][0]:>15.3f}{theirs[1.0][1]:>11.3f}{theirs[5.0][0]:>15.3f}"
        f"{theirs[5.0][1]:>11.3f}{seconds(converged):>12}"
    )
    print(
        "bota per length of data [s]: "
        + ", ".join(f"{k:g}: {v[0]:.2f} %, {v[1]:.2f} mm" for k, v in theirs.items())
    )


if __name__ == "__main__":
    from _targets import run_benchmark

    raise SystemExit(run_benchmark(main))
