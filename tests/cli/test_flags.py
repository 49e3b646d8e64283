"""Flags: bounds with clear messages, degrees named, --sensor-offset stops at the file, -n, xacro
named.
"""

from __future__ import annotations

import re

import numpy as np
import pytest

from ftkin.cli import main
from ftkin.cli.arg_types import join_number_lists
from ftkin.io.csv_table import write_csv

WRENCH = ["fx", "fy", "fz", "mx", "my", "mz"]


def _usage_error(argv, capsys, pattern):
    assert main([str(a) for a in argv]) == 2
    err = capsys.readouterr().err
    assert pattern in err and "Traceback" not in err, err


@pytest.mark.parametrize(
    "n, pattern",
    [
        ("501", "expected 3 to 500 poses"),
        ("10" * 20, "expected 3 to 500 poses"),
        ("2", "at least 3 poses"),
        ("1e3", "whole number of poses"),
    ],
)
def test_plan_n_is_bounded(n, pattern, capsys):
    _usage_error(["plan", "-n", n], capsys, pattern)
    _usage_error(["plan", "--n", n], capsys, pattern)


@pytest.mark.parametrize("g", ["0.5", "98.1", "1e999", "-9.8"])
def test_gravity_outside_1_to_30_is_refused(g, tmp_path, capsys):
    _usage_error(["calibrate", tmp_path / "s.csv", "--g", g], capsys, "argument --g")


@pytest.mark.parametrize("text", ["joint1:-90:90", "joint1:0:180", "joint2:-7:1"])
def test_joint_range_in_degrees_is_named(text, capsys):
    _usage_error(["plan", "-n", "3", "--joint-range", text], capsys, "these look like degrees")


def test_sensor_offset_in_degrees_is_named(capsys):
    _usage_error(
        ["plan", "-n", "3", "--robot", "ur5", "--sensor-offset", "0", "0", "0.05", "0", "0", "90"],
        capsys,
        "these look like degrees",
    )


def test_sensor_offset_stops_at_the_file(arm, truth, tmp_path, capsys):
    assert join_number_lists(["--sensor-offset", "0", "-0.1", "0.05", "s.csv", "-o", "x"]) == [
        "--sensor-offset=0,-0.1,0.05",
        "s.csv",
        "-o",
        "x",
    ]
    assert join_number_lists(["--sensor-offset", "1", "2", "3", "4", "5", "6", "7"]) == [
        "--sensor-offset=1,2,3,4,5,6",
        "7",
    ]
    rng = np.random.default_rng(1)
    from ftkin.kinematics.robots import load_robot

    ur5 = load_robot("ur5", [0.0, 0.0, 0.05])
    q = ur5.random_configurations(5, rng, margin=0.3)
    path = write_csv(
        tmp_path / "s.csv",
        [f"q{i + 1}" for i in range(ur5.nq)] + WRENCH,
        np.hstack([q, truth.predict(ur5.rotation_sensor_to_base(q))]).tolist(),
    )
    assert (
        main(
            [
                "calibrate",
                "--robot",
                "ur5",
                "--sensor-offset",
                "0",
                "0",
                "0.05",
                str(path),
                "--method",
                "linear",
            ]
        )
        == 0
    )
    assert "5 poses" in capsys.readouterr().out
    _usage_error(
        ["calibrate", "--robot", "ur5", "--sensor-offset", "0", "0", str(path)],
        capsys,
        "takes 3 numbers",
    )


def test_xacro_is_named(tmp_path, capsys):
    xacro = tmp_path / "arm.urdf.xacro"
    xacro.write_text(
        '<robot xmlns:xacro="http://www.ros.org/wiki/xacro" name="a"><xacro:include '
        'filename="x"/></robot>'
    )
    _usage_error(
        ["plan", "-n", "3", "--urdf", xacro], capsys, "xacro file, not a URDF: run xacro first"
    )
    hidden = tmp_path / "arm.urdf"
    hidden.write_text(xacro.read_text())
    _usage_error(["plan", "-n", "3", "--urdf", hidden], capsys, "run xacro first")


@pytest.mark.parametrize(
    "argv, pattern",
    [
        (["demo", "--n", "-1"], "at least 3 poses"),
        (["demo", "--n", "100000000000000"], "expected 3 to 500 poses"),
        (["demo", "--readings-per-pose", "0"], "readings per pose"),
        (["demo", "--seed", "-5"], "the seed must be at least 0"),
        (["plan", "-n", "3", "--seed", str(2**64)], "the seed must be below 2**63"),
        (["simulate", "placement", "--dt", "1e-12"], "at most 1,000,000"),
        (["simulate", "placement", "--duration", "1e9"], "at most 1,000,000"),
        (["plan", "-n", "3", "--floor-height", "nan"], "a number in [-100, 100]"),
    ],
)
def test_sizes_and_seeds_are_bounded(argv, pattern, capsys):
    _usage_error(argv, capsys, pattern)


@pytest.mark.parametrize(
    "argv, pattern",
    [
        (["calibrate", ""], "the samples file name is empty"),
        (["calibrate", "s.csv", "--urdf", ""], "the urdf file name is empty"),
        (["calibrate", "s.csv", "--robot", " "], "--robot is empty"),
        (["plan", "-n", "3", "--sensor-frame", ""], "--sensor-frame is empty"),
        (["compensate", "", "s.csv", "-o", "x.csv"], "the calibration file name is empty"),
        (["calibrate", "s.csv", "--package-dir", " "], "--package-dir is empty"),
    ],
)
def test_empty_names_are_refused(argv, pattern, capsys):
    _usage_error(argv, capsys, pattern)


@pytest.mark.parametrize(
    "argv",
    [
        ["robot", "demo", "--push", "nan"],
        [
            "robot",
            "calibrate",
            "--franka",
            "h",
            "--sensor",
            "m:f",
            "-o",
            "c.json",
            "--floor-height",
            "nan",
        ],
        ["robot", "payload", "c.json", "--franka", "h", "--end-effector", "1", "0", "0", "inf"],
        ["calibrate", "s.csv", "--expected-gravity", "0", "0", "nan"],
        ["plan", "-n", "3", "--drift-rate", "nan", "1e-4"],
        ["rezero", "c.json", "s.csv", "--q", "nan", "0", "0", "0", "0", "0"],
    ],
)
def test_no_float_flag_takes_nan_or_inf(argv, capsys):
    """Every float flag is finite at the edge (``type=float`` let ``nan`` through)."""
    assert main([str(a) for a in argv]) == 2
    err = capsys.readouterr().err
    assert re.search(r"expected a (finite|number in \[)", err) and "Traceback" not in err, err


@pytest.mark.parametrize(
    "argv, pattern",
    [
        (["simulate", "placement", "--plot", "run.txt"], "--plot writes .png, got 'run.txt'"),
        (["view", "c.json", "--png", "v.jpg"], "--png writes .png, got 'v.jpg'"),
        (["view", "c.json", "--html", "v.png"], "--html writes .html or .htm, got 'v.png'"),
    ],
)
def test_fixed_format_outputs_need_their_ending(argv, pattern, tmp_path, capsys, monkeypatch):
    """A PNG is not written under another name (``--plot run.txt`` wrote PNG bytes)."""
    monkeypatch.chdir(tmp_path)
    _usage_error(argv, capsys, pattern)
    assert not list(tmp_path.iterdir())  # refused before anything is written


def _parsers():
    """Every parser of the ftkin command, with its command path."""
    import argparse

    from ftkin.cli import build_parser

    def walk(parser, path):
        yield path, parser
        for action in parser._actions:
            if isinstance(action, argparse._SubParsersAction):
                for name, sub in action.choices.items():
                    yield from walk(sub, (*path, name))

    yield from walk(build_parser([]), ())


EACH_COMMAND_ITS_OWN = {
    "-o": "each command writes its own kind of file (the help names it)",
    "--output": "each command writes its own kind of file (the help names it)",
    "--format": "each command's own output formats (plan: csv/yaml/json; export: the registry)",
}


DISTINCT_CONCEPTS = {
    "settle_time": "--settle-time skips the start of a recording's still stretches "
    "(SegmentParameters); --still-settle-time is how long a live arm must be still (Stillness)",
}


def test_every_option_several_commands_take_is_one_definition():
    """A flag means one thing: the same help, default, choices, number of values and type in
    every command that takes it; and one option (its dest) has one long spelling."""
    import argparse
    from collections import defaultdict

    uses, spellings = defaultdict(dict), defaultdict(set)
    for path, parser in _parsers():
        for action in parser._actions:
            if not action.option_strings or action.help == argparse.SUPPRESS:
                continue
            if action.dest == "help":
                continue
            key = (
                action.help,
                repr(action.default),
                repr(action.choices),
                repr(action.nargs),
                getattr(action.type, "__qualname__", repr(action.type)),
                repr(action.metavar),
            )
            long_flags = tuple(flag for flag in action.option_strings if flag.startswith("--"))
            spellings[action.dest].add(long_flags)
            for flag in action.option_strings:
                uses[flag][" ".join(path)] = key
    differing = {
        flag: commands
        for flag, commands in uses.items()
        if flag not in EACH_COMMAND_ITS_OWN and len(set(commands.values())) > 1
    }
    assert differing == {}, "\n".join(
        f"{flag}: "
        + "; ".join(f"{command}: {key[0]!r} default {key[1]}" for command, key in c.items())
        for flag, c in differing.items()
    )
    two_spellings = {
        dest: s for dest, s in spellings.items() if len(s) > 1 and dest not in DISTINCT_CONCEPTS
    }
    assert two_spellings == {}


REMOVED_SPELLINGS = [
    (["extract", "r.bag", "-o", "{out}", "--all"], "--all"),
    (["demo", "--readings", "3"], "--readings 3"),
    (["demo", "--poses", "4"], "--poses 4"),
    (["plan", "--n", "4", "-o", "{out}", "--readings", "3"], "--readings 3"),
    (["simulate", "samples", "-o", "{out}", "--readings", "3"], "--readings 3"),
    (["record", "-o", "{out}", "--readings", "3"], "--readings 3"),
    (["robot", "calibrate", "--dry-run", "-o", "c.json", "--readings", "3"], "--readings 3"),
    (["robot", "calibrate", "--dry-run", "-o", "c.json", "--floor", "0.2"], "--floor 0.2"),
    (["robot", "guide", "c.json", "--franka", "h", "--rate", "100"], "--rate 100"),
    (["robot", "demo", "--poses", "4"], "--poses 4"),
    # a prefix of a flag is no flag either (argparse's allow_abbrev would take it)
    (["simulate", "samples", "-o", "{out}", "--readings-per", "3"], "--readings-per 3"),
    (["robot", "calibrate", "--dry-run", "-o", "c.json", "--floor-h", "0.2"], "--floor-h 0.2"),
    (["extract", "r.bag", "-o", "{out}", "--all-row"], "--all-row"),
]
"""Spellings of the unreleased drafts (``--all``, ``--readings``, ``--floor``, ``--rate``,
``--poses N``) and prefixes of today's flags: each is an unrecognized argument."""


@pytest.mark.parametrize("argv, unrecognized", REMOVED_SPELLINGS)
def test_removed_spellings_and_prefixes_are_refused(argv, unrecognized, tmp_path, capsys):
    """ftkin was never released: no old spelling is kept, and a flag is only taken as spelled."""
    out = tmp_path / "out.csv"
    assert main([a.format(out=out) for a in argv]) == 2
    err = capsys.readouterr().err
    assert f"unrecognized arguments: {unrecognized}" in err and "Traceback" not in err, err
    assert "deprecated" not in err
    assert not out.exists()


def test_every_parser_takes_flags_only_as_spelled_and_hides_none():
    """Every command's parser refuses abbreviations (``allow_abbrev`` off) and lists every flag
    in its ``--help`` (no hidden old spelling)."""
    import argparse

    parsers = list(_parsers())
    assert len(parsers) > 15  # the commands and the robot's and simulate's actions
    for path, parser in parsers:
        assert parser.allow_abbrev is False, path
        hidden = [a.option_strings for a in parser._actions if a.help == argparse.SUPPRESS]
        assert hidden == [], (path, hidden)


@pytest.mark.parametrize("command", [["simulate", "samples"], ["robot", "calibrate", "--dry-run"]])
def test_a_count_given_to_poses_names_n_and_the_advice_works(
    command, tmp_path, monkeypatch, capsys
):
    """``--poses 12`` where no file ``12`` exists is refused naming ``--n 12``, which works; a
    poses file whose name is a number is read (the refusal looks at the disk, not the text)."""
    monkeypatch.chdir(tmp_path)
    argv = [*command, "-o", str(tmp_path / ("c.json" if "robot" in command else "s.csv"))]
    assert main([*argv, "--poses", "12"]) == 2
    err = capsys.readouterr().err
    assert "--poses names a poses file" in err and "--n 12" in err and "Traceback" not in err
    assert main([*argv, "--n", "12"]) == 0
    assert main([*argv, "--poses", " 12"]) == 2  # spaces around the number: the same refusal
    assert "--n 12" in capsys.readouterr().err
    plan = "c.poses.csv" if "robot" in command else None
    if plan is None:
        assert main(["plan", "--n", "5", "-o", str(tmp_path / "p.csv")]) == 0
        plan = "p.csv"
    (tmp_path / "12").write_text((tmp_path / plan).read_text())
    capsys.readouterr()
    assert main([*argv, "--poses", "12"]) == 0
    assert "--n" not in capsys.readouterr().err
    assert main([*argv, "--poses", "missing.csv"]) == 2
    assert "missing.csv: file not found" in capsys.readouterr().err


def test_simulate_drift_is_spelled_with_drift_only(tmp_path, capsys):
    """``simulate --with-drift`` (``--drift`` is ``calibrate``'s drift model; simulate's old
    spelling is gone: ftkin was never released, so no shim)."""
    assert (
        main(["simulate", "samples", "--with-drift", "--n", "4", "-o", str(tmp_path / "d.csv")])
        == 0
    )
    assert "t" in (tmp_path / "d.csv").read_text().splitlines()[0].split(",")
    assert main(["simulate", "samples", "--drift", "--n", "4", "-o", str(tmp_path / "e.csv")]) == 2
    assert "unrecognized arguments: --drift" in capsys.readouterr().err
    assert not (tmp_path / "e.csv").exists()


def test_pose_constraint_flags_are_the_declarations_of_pose_constraints():
    """``plan`` and ``robot calibrate`` build their constraint flags from ``PoseConstraints``:
    the help each parser shows is the declaration's, and the values parse into the field's
    units (degrees on the command line, radians in the field)."""
    import argparse

    from ftkin.cli.declared import help_text
    from ftkin.cli.pose_options import add_constraint_arguments, constraints_from_args
    from ftkin.options import declared_options, field_default
    from ftkin.planning.constraints import PoseConstraints

    parser = argparse.ArgumentParser()
    add_constraint_arguments(parser)
    shown = {action.dest: action.help for action in parser._actions}
    for field, declaration in declared_options(PoseConstraints):
        assert shown[field.name] == help_text(declaration, field_default(field)), field.name
    given = constraints_from_args(
        parser.parse_args(["--max-tilt-deg", "30", "--joint-range", "j1:-0.5:0.25"])
    )
    assert given.max_tilt == pytest.approx(np.pi / 6, abs=1e-15)
    assert given.joint_ranges == (("j1", -0.5, 0.25),)
    assert given.floor_height == pytest.approx(0.1, abs=0)
    assert constraints_from_args(parser.parse_args(["--no-floor"])).floor_height is None
    assert constraints_from_args(parser.parse_args(["--no-self-collision"])).self_collision is False


def test_robot_calibrates_old_joint_range_is_named(capsys):
    argv = ["robot", "calibrate", "--dry-run", "--n", "3", "-o", "c.json"]
    assert main([*argv, "--joint-range", "fr3_joint1", "-0.5", "0.5"]) == 2
    assert "(JOINT LOW HIGH, three words, is the old spelling)" in capsys.readouterr().err


@pytest.mark.parametrize(
    "argv, pattern",
    [
        (["simulate", "samples", "--com", "0", "0", "47"], "within 10 m of the sensor"),
        (["simulate", "samples", "--mount-rpy-deg", "0", "0", "1e9"], "within ±360 [deg]"),
    ],
)
def test_a_simulated_tool_is_one_a_calibration_file_accepts(argv, pattern, capsys, tmp_path):
    _usage_error([*argv, "-o", str(tmp_path / "s.csv")], capsys, pattern)
    assert not (tmp_path / "s.csv").exists()
