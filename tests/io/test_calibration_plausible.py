"""A calibration file that parses but cannot be right: foreign units, an absurd centre of mass, bias
or g.
"""

from __future__ import annotations

import json

import pytest

from ftkin import calibrate
from ftkin.exceptions import CalibrationFileError
from ftkin.io.calibration_file import load_calibration, save_calibration
from ftkin.sim.paper import paper_samples


@pytest.fixture(scope="module")
def document(tmp_path_factory):
    path = tmp_path_factory.mktemp("cal") / "good.json"
    save_calibration(calibrate(paper_samples()), path)
    return json.loads(path.read_text())


@pytest.mark.parametrize(
    ("edit", "match"),
    [
        (
            lambda d: d["units"].update(force_offset="kN, sensor frame"),
            "force_offset is stated in 'kN, sensor frame'",
        ),
        (lambda d: d["units"].update(center_of_mass="mm, sensor frame"), "ftkin files are in 'm'"),
        (lambda d: d.update(units="SI"), "expected an object or null"),
        (
            lambda d: d.update(center_of_mass=[0.0, 0.0, 47.0]),
            "centre of mass is 47 m from the sensor",
        ),
        (lambda d: d.update(force_offset=[0.0, 2e6, 0.0]), r"beyond ±1e\+06"),
        (
            lambda d: (d.update(g=98.0665), d.pop("tool_mass")),
            "g must be between 1 and 30 m/s², got 98.0665",
        ),
    ],
)
def test_implausible_files_are_refused_naming_the_key(document, tmp_path, edit, match):
    edited = json.loads(json.dumps(document))
    edit(edited)
    path = tmp_path / "edited.json"
    path.write_text(json.dumps(edited))
    with pytest.raises(CalibrationFileError, match=match):
        load_calibration(path)


def test_the_middle_dot_and_missing_units_are_fine(document, tmp_path):
    edited = json.loads(json.dumps(document))
    edited["units"]["torque_offset"] = "N·m, sensor frame"
    (tmp_path / "dot.json").write_text(json.dumps(edited))
    assert load_calibration(tmp_path / "dot.json").torque_offset.shape == (3,)
    del edited["units"]
    (tmp_path / "none.json").write_text(json.dumps(edited))
    assert load_calibration(tmp_path / "none.json").tool_weight == pytest.approx(
        document["tool_weight"]
    )
