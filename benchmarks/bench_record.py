"""``ftkin record`` on an arm it does not drive: franky-sim's FR3 moved by this script.

Each repeat starts a simulated FR3 (:class:`ftkin.robot.FrankaSim`: a wrist sensor with bias and
noise, a 1.2 kg tool) and connects one :class:`ftkin.robot.FrankaRobot`. A thread of this
script is the user: it moves the arm through 12 planned poses, waiting at each until the
recorder says "recorded" (franky-sim serves one client: the recorder reads the joint state
through the same robot object, never commanding it). :func:`ftkin.robot.recorder.record_poses`
finds the still phases, records 50 readings at each and calibrates. Beside it, in the same run
and on the same simulator, the peer: :func:`ftkin.robot.calibrate_on_robot` driving the arm
through the same 12 poses (``robot calibrate``). Targets (issue 32's record/calibrate rows,
on franky-sim instead of the UR emulator): mass within 0.5 %, centre of mass within 1 mm, force
bias within 0.05 N, against the simulation's truth.

Then once, faults while recording (the mover injects them 0.3 s into the move to the third
pose): a NaN sensor (stop latency from the injection), a killed simulator (from SIGKILL to the
stop: the robot's clock standing still for its state timeout, 0.3 s here, is the signal; target
0.5 s as issue 32's killed controller), and SIGINT (calibrated from the poses so far, then
``resume=True`` finishes the 12 with no pose twice). Each must leave whole poses only.

Run: ``python benchmarks/bench_record.py [--repeats 2]`` (about 3 minutes). Exit code 1 when a
target row fails, 2 when franky or franky-sim is missing.
"""

from __future__ import annotations

import argparse
import logging
import os
import signal
import tempfile
import threading
import time
from pathlib import Path

import numpy as np

PLAN = {"joint_ranges": {"fr3_joint1": (-0.8, 0.8)}}
POSES, READINGS = 12, 50
STALE_AFTER = 0.5  # Stillness.stale_after (default 0.1 s: a loaded machine pauses the simulation)
STATE_TIMEOUT = 0.3  # FrankaRobot.state_timeout (default 0.1 s, same reason)
FAULT_DELAY = 0.3  # [s] into a move: the arm moving, as the user moves it


class Mover(threading.Thread):
    """The user: to each pose, wait there until the recorder says it is recorded, go on;
    ``action()`` once, :data:`FAULT_DELAY` into the move to pose ``at`` (a fault)."""

    def __init__(self, robot, poses, at=None, action=None):
        super().__init__(daemon=True)
        self.robot, self.poses, self.at, self.action = robot, poses, at, action
        self.recorded = threading.Semaphore(0)
        self.still_at, self.recorded_at, self.fault_time, self.error = [], [], None, None
        self.stopped = False

    def _fault(self):
        self.fault_time = time.monotonic()
        self.action()

    def stop(self):
        """The recording ended: go no further."""
        self.stopped = True
        self.recorded.release()

    def on_event(self, event):
        if event.kind == "recorded":
            self.recorded_at.append(time.monotonic())
            self.recorded.release()

    def run(self):
        from ftkin.robot.stillness import Stillness, wait_still

        try:
            for index, q in enumerate(self.poses):
                if not self.recorded.acquire(timeout=60) or self.stopped:
                    return
                if index == self.at:
                    threading.Timer(FAULT_DELAY, self._fault).start()
                self.robot.move_to(q)
                wait_still(self.robot, Stillness(stale_after=STALE_AFTER))
                self.still_at.append(time.monotonic())
        except Exception as error:  # noqa: BLE001 - a fault injected on purpose ends the move
            self.error = error


def start_at_first_pose(robot, poses):
    from ftkin.robot.stillness import Stillness, wait_still

    robot.move_to(poses[0])
    wait_still(robot, Stillness(stale_after=STALE_AFTER))


def errors(result, truth) -> dict:
    return {
        "mass": abs(result.tool_mass / truth.mass - 1.0) * 100.0,
        "com": float(np.linalg.norm(result.center_of_mass - truth.center_of_mass) * 1e3),
        "bias": float(np.abs(result.force_offset - truth.bias[:3]).max()),
    }


def record_and_peer(repeat: int, folder: Path) -> dict:
    from ftkin.kinematics.fr3 import fr3_arm
    from ftkin.robot import FrankaRobot, FrankaSim, SimSensorSpec, Stillness, calibrate_on_robot
    from ftkin.robot.recorder import record_poses
    from ftkin.robot.session import session_poses

    arm = fr3_arm()
    poses = session_poses(arm, POSES, seed=repeat, readings_per_pose=READINGS, plan_options=PLAN)
    out = {}
    with FrankaSim(sensor=SimSensorSpec(seed=repeat)) as sim:
        robot = FrankaRobot(sim.hostname, realtime=False, speed=0.8, state_timeout=STATE_TIMEOUT)
        start_at_first_pose(robot, poses)
        mover = Mover(robot, poses[1:])
        mover.start()
        started = time.monotonic()
        recording = record_poses(
            sim.sensor,
            robot,
            arm,
            samples_path=folder / f"record{repeat}.csv",
            n_poses=POSES,
            readings_per_pose=READINGS,
            stillness=Stillness(stale_after=STALE_AFTER),
            g=sim.truth.g,
            on_event=mover.on_event,
        )
        out["wall"] = time.monotonic() - started
        mover.join(30)
        delays = np.array(mover.recorded_at[1:]) - np.array(mover.still_at[: POSES - 1])
        out["delay"] = float(np.median(delays) * 1e3)
        out.update({f"record_{k}": v for k, v in errors(recording.calibration, sim.truth).items()})
        peer = calibrate_on_robot(
            robot,
            sim.sensor,
            arm,
            poses=poses,
            readings_per_pose=READINGS,
            samples_path=folder / f"peer{repeat}.csv",
            verify_poses=0,
            stillness=Stillness(stale_after=STALE_AFTER),
            g=sim.truth.g,
        )
        out.update({f"peer_{k}": v for k, v in errors(peer, sim.truth).items()})
    return out


def whole(path, expected: int) -> bool:
    """The file holds poses 0..expected-1, READINGS rows each."""
    from ftkin.io.csv_table import read_table

    ids = np.round(read_table(path).floats(["pose"])[:, 0]).astype(int)
    unique, counts = np.unique(ids, return_counts=True)
    return unique.tolist() == list(range(expected)) and bool(np.all(counts == READINGS))


def fault(kind: str, folder: Path) -> dict:
    from ftkin.exceptions import RecordingInterrupted
    from ftkin.kinematics.fr3 import fr3_arm
    from ftkin.robot import FrankaRobot, FrankaSim, Stillness
    from ftkin.robot.recorder import record_poses
    from ftkin.robot.session import session_poses

    arm = fr3_arm()
    poses = session_poses(arm, 6, seed=7, readings_per_pose=READINGS, plan_options=PLAN)
    path = folder / f"fault-{kind.replace(' ', '-')}.csv"
    with FrankaSim() as sim:
        robot = FrankaRobot(sim.hostname, realtime=False, speed=0.8, state_timeout=STATE_TIMEOUT)
        start_at_first_pose(robot, poses)
        actions = {
            "nan": lambda: sim.sensor.inject("nan"),
            "killed server": sim.kill,
            "SIGINT": lambda: os.kill(os.getpid(), signal.SIGINT),
        }
        mover = Mover(robot, poses[1:], at=1, action=actions[kind])  # starting for pose 3
        mover.start()
        options = {
            "samples_path": path,
            "n_poses": 6,
            "readings_per_pose": READINGS,
            "stillness": Stillness(stale_after=STALE_AFTER),
            "g": sim.truth.g,
        }
        reason = ""
        try:
            recording = record_poses(sim.sensor, robot, arm, on_event=mover.on_event, **options)
            kept = recording.poses_recorded
            calibrated = recording.calibration is not None or "at least 3" in recording.note
        except RecordingInterrupted as error:
            kept, calibrated, reason = error.poses_recorded, True, error.reason
        stopped = time.monotonic()
        mover.stop()
        mover.join(30)
        sim.sensor.inject(None)
        out = {"latency": (stopped - mover.fault_time) * 1e3, "kept": kept, "reason": reason}
        out["whole"] = whole(path, kept) and calibrated
        if kind == "SIGINT":  # the user resumes where the arm stands, then visits the rest
            rest = Mover(robot, poses[kept + 1 :])
            rest.start()
            resumed = record_poses(
                sim.sensor, robot, arm, on_event=rest.on_event, resume=True, **options
            )
            rest.join(30)
            out["whole"] = out["whole"] and whole(path, 6) and resumed.calibration is not None
    return out


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=2, help="recordings (medians are shown)")
    args = parser.parse_args(argv)
    try:
        import franky  # noqa: F401
        import franky_sim  # noqa: F401
    except ImportError:
        print("bench_record: needs franky-control and franky-sim (pip install 'ftkin[franka-sim]')")
        return 2
    logging.basicConfig(level=logging.ERROR)
    started = time.monotonic()
    rows = []
    with tempfile.TemporaryDirectory(prefix="ftkin-bench-record-") as folder:
        folder = Path(folder)
        runs = [record_and_peer(repeat, folder) for repeat in range(args.repeats)]

        def median(key):
            return float(np.median([run[key] for run in runs]))

        for key, name, unit, goal in (
            ("mass", "tool mass error", "%", 0.5),
            ("com", "COM error", "mm", 1.0),
            ("bias", "force bias error", "N", 0.05),
        ):
            value = median(f"record_{key}")
            rows.append(
                (
                    f"record: {name}",
                    value,
                    median(f"peer_{key}"),
                    f"≤ {goal:g} {unit}",
                    value <= goal,
                )
            )
        rows.append((f"record: wall time, {POSES} poses", median("wall"), None, "(info) s", True))
        rows.append(("record: still → recorded", median("delay"), None, "(info) ms", True))
        for kind in ("nan", "killed server", "SIGINT"):
            result = fault(kind, folder)
            goal = {"nan": 10.0, "killed server": 500.0, "SIGINT": 10.0}[kind]
            rows.append(
                (
                    f"fault {kind}: stop latency",
                    result["latency"],
                    None,
                    f"≤ {goal:g} ms",
                    result["latency"] <= goal,
                )
            )
            rows.append(
                (
                    f"fault {kind}: whole poses kept",
                    float(result["kept"]),
                    None,
                    "poses, intact",
                    result["whole"],
                )
            )
    print(
        f"ftkin record benchmark on franky-sim, the arm moved by the script ({args.repeats} "
        f"recordings, medians; {time.monotonic() - started:.0f} s)"
    )
    print(f"{'target':36s} {'record':>10s} {'robot calibrate':>16s}  {'goal':>16s}  result")
    failed = 0
    for name, value, peer, goal, ok in rows:
        failed += not ok
        shown = "" if peer is None else f"{peer:.3f}"
        print(f"{name:36s} {value:10.3f} {shown:>16s}  {goal:>16s}  {'PASS' if ok else 'FAIL'}")
    print(f"{len(rows) - failed} of {len(rows)} rows pass")
    return 1 if failed else 0


if __name__ == "__main__":
    from _targets import run_benchmark

    raise SystemExit(run_benchmark(main))
