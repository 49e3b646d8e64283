"""compensate reads the log against the calibration under the common mistakes: a log in another
convention or unit was compensated into garbage with exit 0 (torques in N·mm gave 102 N·m of
"contact"). A log with real contacts is not questioned: no other reading removes a contact.

The logs are the simulator's readings (its truth, noise and a contact wrench of our choosing) at
FK poses of the bundled arm, written as a logger would, then spoiled by hand.
"""

from __future__ import annotations

import numpy as np
import pytest

from ftkin import SensorNoise, SimulatedSensor, calibrate, save_calibration
from ftkin.cli import main
from ftkin.io.csv_table import read_table, write_csv
from ftkin.sim.sensor import paper_like_truth

WRENCH = ["fx", "fy", "fz", "mx", "my", "mz"]
LBF = 4.4482216152605


@pytest.fixture(scope="module")
def setup(arm, tmp_path_factory):
    folder = tmp_path_factory.mktemp("logs")
    rng = np.random.default_rng(3)
    sensor = SimulatedSensor(paper_like_truth(), SensorNoise.paper())
    poses = arm.random_configurations(12, rng, margin=0.3)
    calibration = folder / "c.json"
    save_calibration(calibrate(sensor.samples_at_configurations(arm, poses, rng, 20)), calibration)
    q = arm.random_configurations(400, rng, margin=0.3)
    contact = np.zeros((400, 6))
    contact[::2] = [0.0, 3.0, 12.0, 0.05, -0.1, 0.2]  # half the rows pushed on
    raw = sensor.read(arm.rotation_sensor_to_base(q), rng, contact)
    return folder, calibration, q, raw, contact


def _log(folder, arm, name, q, raw):
    path = folder / name
    write_csv(path, [*arm.joint_names, *WRENCH], np.column_stack([q, raw]).tolist())
    return path


def test_a_log_with_contacts_is_compensated(setup, arm, capsys):
    folder, calibration, q, raw, contact = setup
    out = folder / "out.csv"
    assert (
        main(
            [
                "compensate",
                str(calibration),
                str(_log(folder, arm, "ok.csv", q, raw)),
                "-o",
                str(out),
            ]
        )
        == 0
    )
    recovered = read_table(out).floats(WRENCH)
    np.testing.assert_allclose(recovered[::2, :3], contact[::2, :3], atol=0.15)  # noise 0.02 N


@pytest.mark.parametrize(
    "name, spoil, named",
    [
        ("negated", lambda raw: -raw, "the readings negated"),
        ("lbf", lambda raw: raw * ([1 / LBF] * 3 + [1] * 3), "forces in lbf"),
        ("nmm", lambda raw: raw * ([1] * 3 + [1000] * 3), "torques in N·mm"),
    ],
)
def test_a_log_in_another_convention_is_refused_naming_it(setup, arm, capsys, name, spoil, named):
    folder, calibration, q, raw, _ = setup
    log = _log(folder, arm, f"{name}.csv", q, spoil(raw))
    out = folder / f"{name}_out.csv"
    assert main(["compensate", str(calibration), str(log), "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert f"the log fits the calibration when read with {named}" in err and "Traceback" not in err
    assert not out.exists()
    flag = ["--no-convention-check"]
    assert main(["compensate", str(calibration), str(log), "-o", str(out), *flag]) == 0


def test_the_library_refuses_as_the_command_does(setup, arm, capsys):
    """The decision is the library's (ftkin.io.log_conventions): the same spoiled log raises
    ConventionMistake from Python with the words the command prints, plus the command's advice;
    the log as given passes both."""
    from ftkin import ConventionMistake, load_calibration
    from ftkin.io.log_conventions import check_log_conventions

    folder, calibration, q, raw, _ = setup
    log = _log(folder, arm, "agree_nmm.csv", q, raw * ([1] * 3 + [1000] * 3))
    with pytest.raises(ConventionMistake) as refused:
        check_log_conventions(read_table(log), arm, load_calibration(calibration))
    assert "torques in N·mm" in refused.value.reading
    out = folder / "agree_out.csv"
    assert main(["compensate", str(calibration), str(log), "-o", str(out)]) == 2
    assert str(refused.value) in capsys.readouterr().err
    good = _log(folder, arm, "agree_ok.csv", q, raw)
    assert check_log_conventions(read_table(good), arm, load_calibration(calibration)) is None
