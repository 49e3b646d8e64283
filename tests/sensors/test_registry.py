"""Sensors by name (``--sensor ati|bota``), typed options, ``MODULE:FACTORY``, and the CLI."""

from __future__ import annotations

import inspect
import time

import numpy as np
import pytest

import ftkin.robot
from ftkin.cli import main
from ftkin.exceptions import InvalidInput
from ftkin.sensors import load_sensor_factory, open_sensor
from ftkin.sensors.registry import BUILT_IN, sensor_entry

NOWHERE = "127.0.0.1:1"  # no robot listens there


@pytest.mark.parametrize("name", BUILT_IN)
def test_every_keyword_of_an_adapter_is_a_declared_option(name):
    entry = sensor_entry(name)
    parameters = inspect.signature(entry.factory).parameters
    assert [option.name for option in entry.options] == list(parameters)
    for option in entry.options:
        default = parameters[option.name].default
        if default is not inspect.Parameter.empty:
            assert isinstance(default, option.type), option.name
        assert option.help and option.type in (str, int, float)
    assert entry.summary and f"'{name}'" in entry.summary  # names its extra


def test_the_contract_as_written():
    from ftkin.sensors import AtiNetFT, BotaSensor

    ati = inspect.signature(AtiNetFT).parameters
    assert list(ati)[:3] == ["host", "rdt_port", "http_port"]
    assert ati["rdt_port"].default == 49152 and ati["http_port"].default == 80
    assert ati["rdt_port"].kind is inspect.Parameter.KEYWORD_ONLY
    assert list(inspect.signature(BotaSensor).parameters)[0] == "config"
    assert ftkin.robot.load_sensor_factory is load_sensor_factory


def test_options_are_parsed_by_their_type(box):
    options = {"host": box.host, "rdt_port": str(box.rdt_port), "http_port": f"{box.http_port}"}
    options["ignore_status_bits"] = "0x80010000"
    options["silence_after"] = "0.2"
    box.set(counts=[2_000_000, 0, 0, 0, 0, 0], status=0x80010000)
    with open_sensor("ati", options) as sensor:
        assert sensor.status_mask == 0x7FFEFFFF and sensor.silence_after == 0.2
        np.testing.assert_allclose(sensor.read()[1], [2, 0, 0, 0, 0, 0], rtol=1e-12)


@pytest.mark.parametrize(
    ("spec", "options", "message"),
    [
        ("ati", {"hots": "x"}, r"no option 'hots'; its options are host \(required\)"),
        ("ati", {}, r"needs --sensor-option host=\.\.\."),
        ("ati", {"host": "h", "rdt_port": "abc"}, "rdt_port must be an integer, got 'abc'"),
        ("ati", {"host": "h", "silence_after": "inf"}, r"silence_after must be a number \[s\]"),
        ("ati", {"host": " "}, "host must not be empty"),
        ("bota", {"configuration": "x"}, "no option 'configuration'.*config"),
        ("bota", {}, r"needs --sensor-option config=\.\.\."),
        ("nope", {}, "unknown sensor 'nope': built in are ati, bota"),
        ("no colon", {}, "unknown sensor"),
        ("a:b:c", {}, "MODULE:FACTORY"),
    ],
)
def test_bad_names_and_options_are_refused_naming_what_is_known(spec, options, message):
    with pytest.raises(InvalidInput, match=message):
        open_sensor(spec, options)


def test_a_factory_still_gets_its_options_as_given(monkeypatch):
    import tests.robot.fakes as fakes

    given = {}
    monkeypatch.setattr(
        fakes, "given_sensor", lambda **options: given.update(options) or fakes.FakeSensor(), False
    )
    sensor = open_sensor("tests.robot.fakes:given_sensor", {"port": "7", "name": "x"})
    assert sensor.read()[1].shape == (6,) and given == {"port": "7", "name": "x"}


def test_the_cli_names_a_built_in_sensor_and_refuses_an_unknown_option(tmp_path, capsys):
    out = str(tmp_path / "calib.json")
    base = ["robot", "calibrate", "--franka", NOWHERE, "--no-realtime", "-o", out]
    assert main([*base, "--sensor", "ati", "--sensor-option", "hots=192.168.1.1"]) == 2
    err = capsys.readouterr().err
    assert "has no option 'hots'" in err and "host (required)" in err and "Traceback" not in err


def test_the_cli_opens_the_emulated_box_then_meets_the_robot(box, tmp_path, capsys):
    out = str(tmp_path / "calib.json")
    argv = ["robot", "calibrate", "--franka", NOWHERE, "--no-realtime", "-o", out]
    argv += ["--sensor", "ati", "--sensor-option", f"host={box.host}"]
    argv += ["--sensor-option", f"rdt_port={box.rdt_port}"]
    argv += ["--sensor-option", f"http_port={box.http_port}"]
    assert main(argv) == 2  # the sensor opened; no robot at NOWHERE
    err = capsys.readouterr().err
    assert "cannot connect to the robot" in err and "Traceback" not in err
    assert box.stats()["commands"].get("2") == 1  # the box was asked to stream
    time.sleep(0.05)
    assert box.stats()["streaming"] is False  # and to stop, when the command ended


@pytest.mark.parametrize(("name", "page"), [("ati", "ati-netft.md"), ("bota", "bota.md")])
def test_the_sensors_page_lists_every_option_with_its_default(name, page):
    from pathlib import Path

    text = (Path(__file__).resolve().parents[2] / "docs" / page).read_text()
    text = text[text.index("## Options") :]
    entry = sensor_entry(name)
    defaults = entry.defaults()
    for option in entry.options:
        row = next(
            (line for line in text.splitlines() if line.startswith(f"| `{option.name}` |")), None
        )
        assert row is not None, f"docs/{page} has no row for {option.name}"
        default = defaults.get(option.name, "(required)")
        assert str(default) in row, f"docs/{page}: {option.name}'s default {default!r} not in {row}"
