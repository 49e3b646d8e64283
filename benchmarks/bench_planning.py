"""Benchmark: planned calibration poses vs the paper's nine orientations and random poses.

For the bundled arm and UR5 (example-robot-data, sensor frame at tool0):
predicted standard error of every parameter (Fisher information, paper's tool
3.15 N with COM 47 mm along sensor z, noise 0.02 N / 0.002 N·m) for the
paper's nine orientations (Table 1), planned 9 and 12 poses, and 9 random
feasible configurations (median over draws); ratios paper / set; bias errors
relative to the σ/√N bound; planning time (median over seeds). Then a
constrained case (floor + tilt limit) where random sampling struggles.

Run: ``.venv/bin/python benchmarks/bench_planning.py``
"""

from __future__ import annotations

import time

import numpy as np

from ftkin import Arm
from ftkin.kinematics.robots import load_robot
from ftkin.planning.constraints import FeasibilityChecker, PoseConstraints
from ftkin.planning.evaluation import evaluate_poses
from ftkin.planning.plan import plan_poses
from ftkin.sim.paper import paper_samples

NAMES = ("ax", "ay", "az", "fx0", "fy0", "fz0", "mx0", "my0", "mz0", "px", "py", "pz")
SEEDS = (0, 1, 2)
RANDOM_DRAWS = 30


def random_feasible(arm, count, rng, **constraints):
    """``count`` random configurations meeting the constraints, and the acceptance rate."""
    checker = FeasibilityChecker(arm, PoseConstraints(**constraints))
    rotations, tried = [], 0
    while len(rotations) < count and tried < 1_000_000:
        tried += 1
        rotation = checker.check(checker.sample(1, rng)[0])
        if rotation is not None:
            rotations.append(rotation)
    return np.array(rotations), count / tried


def timed_plans(arm, n, **constraints):
    times, plans = [], []
    for seed in SEEDS:
        start = time.perf_counter()
        plans.append(plan_poses(arm, n, seed=seed, progress=False, **constraints))
        times.append(time.perf_counter() - start)
    return plans[0], float(np.median(times))


def bias_to_bound(evaluation):
    ratio = evaluation.vector_std[3:9] / evaluation.bias_bound
    return ratio[:3].max(), ratio[3:].max()


def random_sets(arm, rng, **constraints):
    stds, rates = [], []
    for _ in range(RANDOM_DRAWS):
        rotations, rate = random_feasible(arm, 9, rng, **constraints)
        stds.append(evaluate_poses(rotations).vector_std)
        rates.append(rate)
    return np.array(stds), float(np.mean(rates))


def compare(label, arm, paper, **constraints):
    plan9, time9 = timed_plans(arm, 9, **constraints)
    plan12, time12 = timed_plans(arm, 12, **constraints)
    random_stds, acceptance = random_sets(arm, np.random.default_rng(0), **constraints)
    random_std = np.median(random_stds, axis=0)
    sets = {
        "planned 9": plan9.evaluation.vector_std,
        "planned 12": plan12.evaluation.vector_std,
        "random 9": random_std,
    }
    print(f"\n## {label}: {plan9.constraints.describe()}")
    print(
        f"random feasible configurations: {100 * acceptance:.1f} % of uniform joint samples "
        "accepted"
    )
    head = f"{'param':<6}{'paper 9':>11}" + "".join(f"{name:>12}{'ratio':>7}" for name in sets)
    print(head)
    for i, name in enumerate(NAMES):
        row = f"{name:<6}{paper.vector_std[i]:>11.3e}"
        for std in sets.values():
            row += f"{std[i]:>12.3e}{paper.vector_std[i] / std[i]:>7.2f}"
        print(row)
    print()
    random_ratios = paper.vector_std[None] / random_stds
    summary = {
        "planned 9": (plan9.evaluation, paper.vector_std / plan9.evaluation.vector_std, time9),
        "planned 12": (plan12.evaluation, paper.vector_std / plan12.evaluation.vector_std, time12),
    }
    print(
        f"{'set':<12}{'median ratio':>13}{'worst ratio':>12}{'F0/bound':>10}{'M0/bound':>10}"
        f"{'time [s]':>10}"
    )
    for name, (evaluation, ratio, seconds) in summary.items():
        force, torque = bias_to_bound(evaluation)
        print(
            f"{name:<12}{np.median(ratio):>13.2f}{ratio.min():>12.2f}{force:>10.3f}{torque:>10.3f}"
            f"{seconds:>10.2f}"
        )
    bound = paper.bias_bound  # σ/√9, the same for any nine poses
    force_r = np.median((random_stds[:, 3:6] / bound[:3]).max(axis=1))
    torque_r = np.median((random_stds[:, 6:9] / bound[3:]).max(axis=1))
    print(
        f"{'random 9':<12}{np.median(np.median(random_ratios, axis=1)):>13.2f}"
        f"{np.median(random_ratios.min(axis=1)):>12.2f}{force_r:>10.3f}{torque_r:>10.3f}{'':>10}  "
        f"(median of {RANDOM_DRAWS} draws)"
    )
    return plan9, paper.vector_std / plan9.evaluation.vector_std, time12


def targets(label, plan9, ratio, time12):
    force, torque = bias_to_bound(plan9.evaluation)
    checks = {
        "no parameter worse than the paper's nine": ratio.min() >= 1.0,
        "median improvement >= 2.7x": np.median(ratio) >= 2.7,
        "force bias within 5 % of sigma/sqrt(N)": force <= 1.05,
        "torque bias within 5 % of sigma/sqrt(N)": torque <= 1.05,
        "planning n=12 under 10 s": time12 < 10.0,
    }
    for text, ok in checks.items():
        print(f"  [{'PASS' if ok else 'FAIL'}] {label}: {text}")


def main():
    paper = evaluate_poses(paper_samples().rotations)
    print("Predicted standard errors [N, N·m, m]; ratio = paper's nine / set (higher is better);")
    print("tool 3.15 N, COM 47 mm along sensor z, noise 0.02 N / 0.002 N·m, one reading per pose.")
    arms = {"bundled arm (ftkin_c4)": Arm.default(), "UR5 (sensor at tool0)": load_robot("ur5")}
    results = {label: compare(label, arm, paper) for label, arm in arms.items()}
    constrained = dict(floor_height=0.3, max_tilt=np.deg2rad(30.0))
    for label, arm in arms.items():
        compare(f"{label}, constrained", arm, paper, **constrained)
    print("\n## targets (unconstrained, nine planned poses)")
    for label, (plan9, ratio, time12) in results.items():
        targets(label, plan9, ratio, time12)


if __name__ == "__main__":
    from _targets import run_benchmark

    raise SystemExit(run_benchmark(main))
