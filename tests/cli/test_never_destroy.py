"""No ftkin command destroys a file: outputs that name an input, a device, a FIFO or a folder are
refused.
"""

from __future__ import annotations

import os

import numpy as np
import pytest

from ftkin.cli import main
from ftkin.io.atomic import atomic_write_text, check_output_path
from ftkin.io.csv_table import write_csv

WRENCH = ["fx", "fy", "fz", "mx", "my", "mz"]


@pytest.fixture(scope="module")
def files(tmp_path_factory, arm, truth):
    """A samples CSV (joint columns) and its calibration file."""
    folder = tmp_path_factory.mktemp("never_destroy")
    rng = np.random.default_rng(3)
    q = arm.random_configurations(6, rng, margin=0.3)
    wrenches = truth.predict(arm.rotation_sensor_to_base(q))
    samples = write_csv(
        folder / "s.csv",
        ["pose", *[f"q{i + 1}" for i in range(arm.nq)], *WRENCH],
        [[i, *map(float, a), *map(float, b)] for i, (a, b) in enumerate(zip(q, wrenches))],
    )
    calibration = folder / "c.json"
    assert main(["calibrate", str(samples), "--method", "linear", "-o", str(calibration)]) == 0
    return samples, calibration


def _refused(argv, capsys, protected, pattern):
    before = {path: path.read_bytes() for path in protected}
    assert main([str(a) for a in argv]) == 2
    err = capsys.readouterr().err
    assert err.startswith("ftkin: error: ") and pattern in err, err
    assert "Traceback" not in err
    for path, content in before.items():
        assert path.read_bytes() == content, f"{path} was changed"


def test_output_naming_an_input_is_refused_for_every_command(files, tmp_path, capsys):
    samples, calibration = files
    link = tmp_path / "link.csv"
    link.symlink_to(samples)
    hard = tmp_path / "hard.json"
    os.link(calibration, hard)
    cases = [
        (["calibrate", samples, "-o", samples], samples),
        (["calibrate", link, "-o", samples], samples),  # through a symlink
        (["compensate", calibration, samples, "-o", samples], samples),
        (["compensate", calibration, samples, "-o", calibration], calibration),
        (["compensate", hard, samples, "-o", calibration], calibration),  # through a hard link
        (["export", calibration, "--format", "ft-calib", "-o", calibration], calibration),
        (["extract", samples, "-o", link], samples),
        (["report", calibration, samples, "-o", samples], samples),
        (["view", calibration, samples, "--html", calibration], calibration),
        (["view", calibration, "--replay", samples, "--png", samples], samples),
        (["simulate", "recording", "--trajectory", samples, "-o", samples], samples),
    ]
    for argv, victim in cases:
        _refused(argv, capsys, [victim, samples, calibration], "refusing to overwrite an input")


def test_outputs_that_are_not_regular_files_are_refused(files, tmp_path, capsys):
    samples, calibration = files
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    folder = tmp_path / "folder"
    folder.mkdir()
    for target, kind in ((fifo, "FIFO"), (folder, "folder"), ("/dev/null", "character device")):
        _refused(
            ["export", calibration, "--format", "admittance", "-o", target],
            capsys,
            [calibration],
            kind,
        )
        _refused(["plan", "-n", "3", "--no-self-collision", "-o", target], capsys, [], kind)
    assert os.path.exists("/dev/null") and not os.path.isfile("/dev/null")
    assert fifo.is_fifo() and folder.is_dir()


def test_empty_output_name_is_refused(files, capsys):
    samples, calibration = files
    _refused(["calibrate", samples, "-o", ""], capsys, [samples], "file name is empty")
    _refused(
        ["export", calibration, "--format", "ft-calib", "-o", "  "],
        capsys,
        [calibration],
        "file name is empty",
    )


def test_two_outputs_naming_one_file_are_refused(files, tmp_path, capsys):
    samples, calibration = files
    out = tmp_path / "same.png"
    _refused(["simulate", "placement", "-o", out, "--plot", out], capsys, [], "both name")
    assert not out.exists()


def test_symlink_output_is_written_through_atomically(files, tmp_path, capsys):
    samples, calibration = files
    target_folder = tmp_path / "elsewhere"
    target_folder.mkdir()
    target = target_folder / "params.yaml"
    target.write_text("old\n")
    link = tmp_path / "params.yaml"
    link.symlink_to(target)
    assert main(["export", str(calibration), "--format", "ft-calib", "-o", str(link)]) == 0
    assert link.is_symlink() and os.readlink(link) == str(target)
    assert "gripper_mass" in target.read_text()
    assert sorted(p.name for p in target_folder.iterdir()) == [
        "params.yaml"
    ]  # no temp file left behind


def test_library_writer_shares_the_check(tmp_path):
    from ftkin.exceptions import InvalidInput

    with pytest.raises(InvalidInput, match="is a folder"):
        atomic_write_text(tmp_path, "x")
    with pytest.raises(InvalidInput, match="file name is empty"):
        check_output_path("")
    data = tmp_path / "data.csv"
    data.write_text("a\n")
    with pytest.raises(InvalidInput, match="same file"):
        check_output_path(tmp_path / "." / "data.csv", [data])
    assert (
        check_output_path(tmp_path / "new.csv", [data, tmp_path / "missing.csv"])
        == tmp_path / "new.csv"
    )


def test_every_option_that_names_a_file_to_read_is_protected():
    """An option or argument whose value is a file the command reads is an input of
    ``check_outputs`` (``--trajectory`` of ``simulate recording`` was missing).
    """
    import argparse
    import re

    from ftkin.cli import INPUT_OPTIONS, OUTPUT_OPTIONS, build_parser

    reads = re.compile(r"\.(csv|json)$|^(RECORDING|PATH|TRAJ)")  # not --sg-window SAMPLES
    missing = []

    def walk(parser, path):
        for action in parser._actions:
            if isinstance(action, argparse._SubParsersAction):
                for name, sub in action.choices.items():
                    walk(sub, [*path, name])
            elif isinstance(action.metavar, str) and reads.search(action.metavar):
                if action.dest not in (*INPUT_OPTIONS, *OUTPUT_OPTIONS):
                    missing.append(f"{' '.join(path)} {action.dest}")

    walk(build_parser(), [])
    assert not missing, missing
