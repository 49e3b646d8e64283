"""Fuzz ftkin's file readers for a fixed budget and print how many inputs were tried.

Mutates valid files (byte edits, truncation, duplicated or dropped lines,
structured JSON edits) and feeds them to the readers: samples CSVs (a continuous
recording among them), moving recordings (``calibrate --dynamic``), calibration
JSON and ROS 2 bags. Every input must end in a
result with finite numbers or an ``ftkin.FtkinError``; anything else (a numpy,
Pinocchio or Python traceback) is a bug: the script prints it and exits 1.

    python benchmarks/fuzz_readers.py [--seconds 60] [--seed 0]
"""

from __future__ import annotations

import argparse
import json
import logging
import random
import sys
import tempfile
import time
import traceback
import warnings
from pathlib import Path

import numpy as np

import ftkin
from ftkin.io.calibration_file import calibration_to_dict, load_calibration
from ftkin.io.motion_recording import load_motion_csv
from ftkin.io.samples_csv import load_samples
from ftkin.io.static_segments import SegmentParameters
from ftkin.sim.paper import paper_calibration, paper_csv_path

ALPHABET = list(",\n\r#.-+eE0123456789 \t\"'") + [
    "nan",
    "inf",
    "-inf",
    "1e999",
    "\x00",
    "é",
    "pose",
    "fx",
    "q1",
    "alpha",
]


def mutate_text(text: str, rng: random.Random) -> str:
    """One to four random edits of a text."""
    for _ in range(rng.randint(1, 4)):
        if not text:
            return rng.choice(ALPHABET)
        kind = rng.randrange(7)
        i = rng.randrange(len(text))
        if kind == 0:
            text = text[:i] + text[i + 1 :]
        elif kind == 1:
            text = text[:i] + rng.choice(ALPHABET) + text[i:]
        elif kind == 2:
            text = text[:i]
        elif kind == 3:
            lines = text.splitlines(keepends=True)
            j = rng.randrange(len(lines))
            lines.insert(j, lines[rng.randrange(len(lines))])
            text = "".join(lines)
        elif kind == 4:
            lines = text.splitlines(keepends=True)
            del lines[rng.randrange(len(lines))]
            text = "".join(lines)
        elif kind == 5:
            text = text[:i] + rng.choice(ALPHABET) + text[i + 1 :]
        else:
            j = rng.randrange(len(text))
            text = text[: min(i, j)] + text[max(i, j) :]
    return text


def mutate_document(document, rng: random.Random):
    """A structured edit of a JSON document: drop, retype or corrupt one value, at any depth (the
    nested ``diagnostics``, ``drift``, ``kinematics`` and ``poses`` objects too).
    """
    document = json.loads(json.dumps(document))
    parent = document
    while rng.random() < 0.5:  # descend into a nested object now and then
        nested = [key for key, value in parent.items() if isinstance(value, dict) and value]
        if not nested:
            break
        parent = parent[rng.choice(nested)]
    key = rng.choice(list(parent))
    replacements = [None, "text", "1.5", -1, 0, 1e308, [], {}, [1.0], [[1.0, 2.0]], True, 99]
    replacements += [float("nan"), [None], [True], 2**64, -(2**63) - 1]
    kind = rng.randrange(3)
    if kind == 0:
        del parent[key]
    elif kind == 1 or not (isinstance(parent[key], list) and parent[key]):
        parent[key] = rng.choice(replacements)
    else:
        parent[key][rng.randrange(len(parent[key]))] = rng.choice(replacements)
    return document


def write_small_bag(path: Path, arm, seed: int) -> Path:
    """A bare .mcap with three static poses (joint states 50 Hz, wrenches 100 Hz), 6 s in all."""
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    from ftkin.calibration.information import SensorNoise
    from ftkin.sim.sensor import SimulatedSensor, paper_like_truth

    store = get_typestore(Stores.ROS2_HUMBLE)
    types = store.types
    rng = np.random.default_rng(seed)
    poses = arm.random_configurations(3, rng, margin=0.3)
    sensor = SimulatedSensor(paper_like_truth(), SensorNoise.paper())

    def header(t):
        ns = int(t * 1e9)
        stamp = types["builtin_interfaces/msg/Time"](sec=ns // 10**9, nanosec=ns % 10**9)
        return types["std_msgs/msg/Header"](stamp=stamp, frame_id="ft_sensor")

    folder = path.parent / "bag"
    with Writer(folder, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        joints = writer.add_connection(
            "/joint_states", "sensor_msgs/msg/JointState", typestore=store
        )
        wrench = writer.add_connection(
            "/ft_sensor/wrench", "geometry_msgs/msg/WrenchStamped", typestore=store
        )
        for t in np.arange(0.0, 6.0, 0.02):
            q = poses[min(int(t // 2.0), 2)]
            message = types["sensor_msgs/msg/JointState"](
                header=header(100.0 + t),
                name=list(arm.joint_names),
                position=q,
                velocity=np.zeros(0),
                effort=np.zeros(0),
            )
            writer.write(
                joints,
                int((100.0 + t) * 1e9),
                store.serialize_cdr(message, "sensor_msgs/msg/JointState"),
            )
        for t in np.arange(0.005, 6.0, 0.01):
            w = sensor.read(arm.rotation_sensor_to_base(poses[min(int(t // 2.0), 2)]), rng)[0]
            vector = lambda v: types["geometry_msgs/msg/Vector3"](
                x=float(v[0]), y=float(v[1]), z=float(v[2])
            )  # noqa: E731
            message = types["geometry_msgs/msg/WrenchStamped"](
                header=header(100.0 + t),
                wrench=types["geometry_msgs/msg/Wrench"](force=vector(w[:3]), torque=vector(w[3:])),
            )
            writer.write(
                wrench,
                int((100.0 + t) * 1e9),
                store.serialize_cdr(message, "geometry_msgs/msg/WrenchStamped"),
            )
    return next(folder.glob("*.mcap"))


def mutate_bytes(data: bytes, rng: random.Random) -> bytes:
    """One to four byte edits: flip, overwrite, delete a run, duplicate a run, truncate."""
    data = bytearray(data)
    for _ in range(rng.randint(1, 4)):
        if not data:
            break
        i = rng.randrange(len(data))
        kind = rng.randrange(5)
        if kind == 0:
            data[i] ^= 1 << rng.randrange(8)
        elif kind == 1:
            data[i] = rng.randrange(256)
        elif kind == 2:
            del data[i : i + rng.randint(1, 64)]
        elif kind == 3:
            data[i:i] = data[i : i + rng.randint(1, 64)]
        else:
            del data[i:]
    return bytes(data)


def check_samples(loaded) -> None:
    samples = loaded.samples
    assert np.all(np.isfinite(samples.wrenches)) and np.all(np.isfinite(samples.rotations)), (
        "non-finite samples"
    )


def check_calibration(result) -> None:
    assert np.all(np.isfinite(result.to_vector())), "non-finite calibration"


def check_motion(motion) -> None:
    for values in (motion.wrenches, motion.rotations, motion.velocities, motion.accelerations):
        assert np.all(np.isfinite(values)), "non-finite motion samples"


def _motion_seed(arm) -> str:
    """A moving recording (``calibrate --dynamic``): 100 Hz, sines on every joint, the rates
    given as ``<joint>_vel``/``<joint>_acc`` (what ``plan --excitation`` writes)."""
    times = np.arange(60) / 100.0
    phase = 2 * np.pi * times[:, None] + np.arange(arm.nq)[None, :]
    q, dq, ddq = 0.3 * np.sin(phase), 0.6 * np.pi * np.cos(phase), -1.2 * np.pi**2 * np.sin(phase)
    names = arm.joint_names
    header = ["t", *names, *(f"{n}_vel" for n in names), *(f"{n}_acc" for n in names)]
    header += ["fx", "fy", "fz", "mx", "my", "mz"]
    rows = np.column_stack([times, q, dq, ddq, np.tile([0.1, 0.2, 3.1, 0.0, 0.0, 0.0], (60, 1))])
    return "\n".join([",".join(header), *(",".join(f"{v:.9g}" for v in row) for row in rows)])


def _read_bag_quietly(path: Path, arm):
    from ftkin.io.bags import bag_samples

    return bag_samples(path, arm, progress=False)


def run(seconds: float, seed: int) -> int:
    logging.disable(logging.WARNING)  # readers log warnings about odd but accepted input
    warnings.simplefilter("ignore", RuntimeWarning)  # overflow on the way to a refusal
    rng = random.Random(seed)
    workdir = Path(tempfile.mkdtemp(prefix="ftkin-fuzz-"))
    csv_seeds = [paper_csv_path().read_text()]
    arm = ftkin.Arm.default()
    q = np.random.default_rng(seed).uniform(-1, 1, (4, arm.nq))
    joint_lines = [",".join(arm.joint_names + ["pose", "fx", "fy", "fz", "mx", "my", "mz"])]
    for i, row in enumerate(q):
        joint_lines.append(",".join(f"{v:.6f}" for v in row) + f",{i},0.1,0.2,3.1,0.01,0.02,0.03")
    csv_seeds.append("\n".join(joint_lines) + "\n")
    quat_seed = (
        "qw,qx,qy,qz,fx,fy,fz,mx,my,mz\n1,0,0,0,0,0,3,0,0,0\n"
        "0,1,0,0,0,0,-3,0,0,0\n0.7071,0.7071,0,0,0,3,0,0,0,0\n"
    )
    csv_seeds.append(quat_seed)
    still = np.repeat(q, 15, axis=0)  # a continuous recording at 10 Hz: 1.5 s holds
    recording = [",".join(["t", *arm.joint_names, "fx", "fy", "fz", "mx", "my", "mz"])]
    for i, row in enumerate(still):
        recording.append(
            f"{i / 10:.1f}," + ",".join(f"{v:.6f}" for v in row) + ",0.1,0.2,3.1,0,0,0"
        )
    csv_seeds.append("\n".join(recording) + "\n")
    calibration_document = calibration_to_dict(paper_calibration())
    json_seed = json.dumps(calibration_document, indent=2)
    motion_seed = _motion_seed(arm)

    counts = {"csv": 0, "json-text": 0, "json-structured": 0, "motion-csv": 0}
    bag_seed = None
    try:
        bag_seed = write_small_bag(workdir / "seed.mcap", arm, seed).read_bytes()
        counts["bag"] = 0
    except ImportError:
        print("rosbags not installed: bag reader not fuzzed (pip install 'ftkin[bags]')")
    outcomes = {"ok": 0, "ftkin error": 0}
    deadline = time.monotonic() + seconds
    path = workdir / "input"
    while time.monotonic() < deadline:
        target = rng.choice(list(counts))
        target_path = path
        if target == "csv":
            path.write_text(mutate_text(rng.choice(csv_seeds), rng), errors="surrogateescape")
            reader, check = (lambda p: load_samples(p, arm, SegmentParameters())), check_samples
        elif target == "bag":
            bag_path = workdir / "input.mcap"
            bag_path.write_bytes(mutate_bytes(bag_seed, rng))
            target_path = bag_path
            reader, check = (lambda p: _read_bag_quietly(p, arm)), check_samples
        elif target == "motion-csv":
            path.write_text(mutate_text(motion_seed, rng), errors="surrogateescape")
            reader, check = (lambda p: load_motion_csv(p, arm).motion_samples(arm)), check_motion
        elif target == "json-text":
            path.write_text(mutate_text(json_seed, rng))
            reader, check = load_calibration, check_calibration
        else:
            path.write_text(json.dumps(mutate_document(calibration_document, rng)))
            reader, check = load_calibration, check_calibration
        counts[target] += 1
        try:
            check(reader(target_path))
            outcomes["ok"] += 1
        except ftkin.FtkinError:
            outcomes["ftkin error"] += 1
        except Exception:
            print(f"BUG: {target} input raised a non-ftkin error; input kept at {path}")
            traceback.print_exc()
            return 1
    total = sum(counts.values())
    print(f"{'reader':<20}{'inputs':>10}")
    for name, count in counts.items():
        print(f"{name:<20}{count:>10}")
    print(f"{'total':<20}{total:>10}   ({total / seconds:.0f}/s, seed {seed})")
    print(
        f"outcomes: {outcomes['ok']} accepted with finite values, {outcomes['ftkin error']} "
        "refused with an ftkin error, 0 other"
    )
    return 0


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--seconds", type=float, default=60.0, help="time budget (default: %(default)s)"
    )
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    return run(args.seconds, args.seed)


if __name__ == "__main__":
    sys.exit(main())
