"""No Python traceback ever reaches a CLI user: closed pipes, huge cells, deep JSON, huge numbers,
extreme values.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from ftkin.cli import COMMAND_MODULES, main
from ftkin.io.csv_table import write_csv

WRENCH = ["fx", "fy", "fz", "mx", "my", "mz"]
ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def files(tmp_path_factory, arm, truth):
    folder = tmp_path_factory.mktemp("no_traceback")
    rng = np.random.default_rng(5)
    q = np.repeat(arm.random_configurations(6, rng, margin=0.3), 2, axis=0)
    wrenches = truth.predict(arm.rotation_sensor_to_base(q)) + rng.normal(scale=0.01, size=(12, 6))
    samples = write_csv(
        folder / "s.csv",
        ["pose", *[f"q{i + 1}" for i in range(arm.nq)], *WRENCH],
        [[i // 2, *map(float, a), *map(float, b)] for i, (a, b) in enumerate(zip(q, wrenches))],
    )
    calibration = folder / "c.json"
    assert main(["calibrate", str(samples), "-o", str(calibration)]) == 0
    return folder, samples, calibration


def _commands(
    folder: Path, samples: Path, calibration: Path
) -> dict[str, tuple[list[str], Path | None]]:
    """Every subcommand, with small arguments, and the file it must still write."""
    s, c = str(samples), str(calibration)
    return {
        "calibrate": (["calibrate", s, "-o", str(folder / "c2.json")], folder / "c2.json"),
        "compensate": (["compensate", c, s, "-o", str(folder / "o.csv")], folder / "o.csv"),
        "paper": (["paper"], None),
        "demo": (
            ["demo", "--n", "6", "--readings-per-pose", "3", "-o", str(folder / "d.json")],
            folder / "d.json",
        ),
        "extract": (["extract", s, "-o", str(folder / "e.csv")], folder / "e.csv"),
        "export": (
            ["export", c, "--format", "ft-calib", "-o", str(folder / "x.yaml")],
            folder / "x.yaml",
        ),
        "report": (["report", c, s, "-o", str(folder / "r.png")], folder / "r.png"),
        "plan": (
            ["plan", "-n", "3", "--no-self-collision", "-o", str(folder / "p.csv")],
            folder / "p.csv",
        ),
        "evaluate-poses": (["evaluate-poses", s], None),
        "view": (["view", c, s, "--html", str(folder / "v.html"), "--no-wait"], folder / "v.html"),
        "simulate": (
            ["simulate", "placement", "--duration", "0.3", "-o", str(folder / "run.csv")],
            folder / "run.csv",
        ),
        "doctor": (["doctor", s], None),
        "rezero": (
            [
                "rezero",
                c,
                "--q",
                *["0.3"] * 6,
                "--wrench",
                "0.5",
                "-0.2",
                "-3.0",
                "0.01",
                "0.02",
                "0.0",
                "-o",
                str(folder / "z.json"),
            ],
            folder / "z.json",
        ),
        "robot": (["robot", "calibrate", "--help"], None),  # the rest needs a robot: tests/robot
        "record": (
            ["record", "--help"],
            None,
        ),  # the rest needs a sensor: tests/robot/test_record.py
        "--help": (["--help"], None),
    }


_DRIVER = r"""
import io, json, os, subprocess, sys
from ftkin.cli import main

results = {}
for name, argv in json.loads(sys.argv[1]).items():
    head = subprocess.Popen(["head", "-1"], stdin=subprocess.PIPE, stdout=subprocess.PIPE)
    saved = os.dup(1)
    os.dup2(head.stdin.fileno(), 1)
    head.stdin.close()
    sys.stdout = io.TextIOWrapper(io.FileIO(1, "w", closefd=False), write_through=True,
    line_buffering=True)
    try:
        code = main(argv)
        sys.stdout.flush()
    except BaseException as error:  # anything escaping main is a failure
        code = repr(error)
    finally:
        os.dup2(saved, 1)
        os.close(saved)
        sys.stdout = sys.__stdout__
    out = head.stdout.read().decode()
    head.wait(timeout=60)
    results[name] = [code, out]
print(json.dumps(results))
"""


def test_every_subcommand_piped_into_head(files):
    """Each subcommand's stdout into a real ``head -1``: one line out, no traceback, exit 0, the -o
    file written.

    One interpreter runs them all (importing pinocchio once keeps the test fast): for each command,
    fd 1 becomes the write end of a pipe into a fresh ``head -1`` process, unbuffered, so writes
    after
    the first line meet a closed pipe.
    """
    folder, samples, calibration = files
    commands = _commands(folder, samples, calibration)
    assert set(COMMAND_MODULES) <= set(commands)
    env = {**os.environ, "PYTHONPATH": str(ROOT), "MPLBACKEND": "Agg"}
    argvs = {name: argv for name, (argv, _) in commands.items()}
    process = subprocess.run(
        [sys.executable, "-c", _DRIVER, json.dumps(argvs)],
        env=env,
        cwd=folder,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert "Traceback" not in process.stderr and "Exception ignored" not in process.stderr, (
        process.stderr
    )
    results = json.loads(process.stdout.splitlines()[-1])
    for name, (code, out) in results.items():
        assert code == 0, f"{name}: {code} {process.stderr}"
        assert len(out.splitlines()) == 1, f"{name}: {out!r}"
        written = commands[name][1]
        assert written is None or written.stat().st_size > 0, f"{name} did not write {written}"


def test_entry_point_into_head(tmp_path):
    """The real command line: ``python -m ftkin.cli paper | head -1`` exits 0 with no traceback."""
    env = {**os.environ, "PYTHONPATH": str(ROOT), "PYTHONUNBUFFERED": "1"}
    command = f"set -o pipefail; '{sys.executable}' -m ftkin.cli paper | head -1"
    process = subprocess.run(
        ["bash", "-c", command], env=env, cwd=tmp_path, capture_output=True, text=True, timeout=120
    )
    assert process.returncode == 0, process.stderr
    assert "Traceback" not in process.stderr and "Exception ignored" not in process.stderr, (
        process.stderr
    )
    assert len(process.stdout.splitlines()) == 1


class _ClosedPipe:
    """A stdout whose reader has gone: every write raises BrokenPipeError (deterministic, in
    process).
    """

    def write(self, text):
        raise BrokenPipeError(32, "Broken pipe")

    def flush(self):
        raise BrokenPipeError(32, "Broken pipe")


def test_closed_stdout_in_process_finishes_the_work(files, monkeypatch, capsys):
    folder, samples, calibration = files
    out = folder / "closed.yaml"
    monkeypatch.setattr(sys, "stdout", _ClosedPipe())
    assert main(["export", str(calibration), "--format", "admittance", "-o", str(out)]) == 0
    assert "gravity_compensation" in out.read_text()


def _one_line_error(argv, capsys, pattern) -> str:
    assert main([str(a) for a in argv]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1, err
    assert err.startswith("ftkin: error: ") and pattern in err, err
    return err


def test_huge_csv_cell(files, tmp_path, capsys):
    _, samples, _ = files
    text = samples.read_text().splitlines()
    text[3] = "x" * 200_000 + text[3][1:]
    bad = tmp_path / "huge.csv"
    bad.write_text("\n".join(text) + "\n")
    _one_line_error(["calibrate", bad], capsys, "line 4: cannot parse the CSV")
    nul = tmp_path / "nul.csv"
    nul.write_text(samples.read_text().replace("\n1,", "\n1\0,", 1))
    _one_line_error(["calibrate", nul], capsys, "is not a number")


def test_deeply_nested_json(files, tmp_path, capsys):
    _, samples, _ = files
    for depth in (100_000, 2_000):
        bad = tmp_path / f"deep{depth}.json"
        bad.write_text("[" * depth + "]" * depth)
        _one_line_error(
            ["export", bad, "--format", "ft-calib", "-o", tmp_path / "x.yaml"], capsys, str(bad)
        )
        _one_line_error(["compensate", bad, samples, "-o", tmp_path / "x.csv"], capsys, str(bad))


def test_huge_integers(files, tmp_path, capsys):
    folder, samples, calibration = files
    text = samples.read_text().splitlines()
    text[1] = "1" + "0" * 30 + text[1][1:]  # pose id 10**30
    bad = tmp_path / "pose.csv"
    bad.write_text("\n".join(text) + "\n")
    _one_line_error(["calibrate", bad], capsys, "is too large")
    document = json.loads(calibration.read_text())
    for edit, key in (
        (lambda d: d["diagnostics"].__setitem__("dof", 10**400), "diagnostics"),
        (lambda d: d["poses"].__setitem__("ids", [10**30] * len(d["poses"]["ids"])), "poses.ids"),
        (lambda d: d.__setitem__("sample_count", 10**30), "sample_count"),
        (lambda d: d.__setitem__("g", 10**400), "'g'"),
    ):
        changed = json.loads(json.dumps(document))
        edit(changed)
        path = tmp_path / "huge.json"
        path.write_text(json.dumps(changed).replace("1" + "0" * 400, "1e999"))
        _one_line_error(
            ["export", path, "--format", "ft-calib", "-o", tmp_path / "x.yaml"], capsys, key
        )


def test_extreme_values_are_refused_before_the_numerics(files, tmp_path, capsys):
    _, samples, _ = files
    _one_line_error(
        ["calibrate", samples, "--noise-force", "1e-300", "--noise-torque", "1e-3"],
        capsys,
        "force_std must be between",
    )
    _one_line_error(
        ["calibrate", samples, "--noise-force", "1e-3", "--noise-torque", "1e300"],
        capsys,
        "torque_std must be between",
    )
    _one_line_error(
        ["plan", "-n", "4", "--tool-weight", "1e308", "--no-self-collision"],
        capsys,
        "tool_weight must be between",
    )
    _one_line_error(
        ["evaluate-poses", samples, "--noise-force", "1e-300", "--noise-torque", "1e-3"],
        capsys,
        "force_std must be between",
    )
    _one_line_error(  # one without the other: refused, as calibrate refuses it
        ["evaluate-poses", samples, "--noise-force", "0.05"], capsys, "give both --noise-force"
    )
    text = samples.read_text().splitlines()
    cells = text[2].split(",")
    cells[-3] = "1e300"
    text[2] = ",".join(cells)
    bad = tmp_path / "huge_reading.csv"
    bad.write_text("\n".join(text) + "\n")
    _one_line_error(["calibrate", bad], capsys, "beyond ±1e+06")


def test_unforeseen_error_is_one_line(files, monkeypatch, capsys):
    import numpy as np

    from ftkin.cli import paper

    def broken(args):
        raise np.linalg.LinAlgError("Singular matrix")

    monkeypatch.setattr(paper, "run", broken)
    assert main(["paper"]) == 2
    err = capsys.readouterr().err
    assert err.strip() == (
        "ftkin: error: the numbers are too extreme for the linear algebra (a matrix became "
        "singular) "
        "(LinAlgError: Singular matrix)"
    )

    def bug(args):
        raise AttributeError("no attribute 'x'")

    monkeypatch.setattr(paper, "run", bug)
    assert main(["paper"]) == 3
    err = capsys.readouterr().err
    assert (
        err.startswith("ftkin: error: unexpected internal error (AttributeError")
        and "Traceback" not in err
    )
