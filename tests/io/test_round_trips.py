"""What ftkin writes, ftkin reads back with the same meaning (one test per file kind not covered
beside its reader: the excitation plan's rates, the compensated log).
"""

from __future__ import annotations

import numpy as np
import pytest

from ftkin.cli import main
from ftkin.io.csv_table import read_table, write_csv
from ftkin.io.motion_recording import load_motion_csv
from ftkin.io.samples_csv import load_samples


@pytest.fixture(scope="module")
def excitation(tmp_path_factory):
    path = tmp_path_factory.mktemp("excitation") / "plan.csv"
    options = ["--duration", "2", "--rate", "50", "--period", "2", "--harmonics", "2"]
    assert main(["plan", "--excitation", *options, "--iterations", "2", "-o", str(path)]) == 0
    return path


def test_excitation_rates_are_read_as_the_recordings_rates(excitation, arm, truth):
    table = read_table(excitation)
    q = table.floats(arm.joint_names)
    wrenches = truth.predict(arm.rotation_sensor_to_base(q))
    recording = excitation.with_name("recording.csv")
    write_csv(
        recording,
        [*table.header, "fx", "fy", "fz", "mx", "my", "mz"],
        [[*row, *w] for row, w in zip(table.rows, wrenches.tolist())],
    )
    motion = load_motion_csv(recording, arm)
    names = arm.joint_names
    np.testing.assert_allclose(
        motion.joint_velocities, table.floats([f"{n}_vel" for n in names]), rtol=1e-12
    )
    np.testing.assert_allclose(
        motion.joint_accelerations, table.floats([f"{n}_acc" for n in names]), rtol=1e-12
    )


def test_compensated_log_keeps_the_input_columns(tmp_path, arm, truth, rng):
    from ftkin import save_calibration
    from ftkin.calibration.result import CalibrationResult

    q = arm.random_configurations(5, rng, margin=0.3)
    wrenches = truth.predict(arm.rotation_sensor_to_base(q))
    log = tmp_path / "log.csv"
    write_csv(log, [*arm.joint_names, "fx", "fy", "fz", "mx", "my", "mz"], np.hstack([q, wrenches]))
    calibration = tmp_path / "c.json"
    save_calibration(CalibrationResult(**_parameters(truth)), calibration)
    out = tmp_path / "out.csv"
    assert main(["compensate", str(calibration), str(log), "-o", str(out)]) == 0
    written = load_samples(out, arm, segments=None)  # fx..mz now hold the contact wrench
    np.testing.assert_allclose(written.samples.wrenches, 0.0, atol=1e-9)  # no contact [N, N·m]
    np.testing.assert_allclose(written.samples.joint_positions, q, rtol=1e-12)


def _parameters(model) -> dict:
    return dict(
        force_offset=model.force_offset,
        torque_offset=model.torque_offset,
        gravity_in_base=model.gravity_in_base,
        center_of_mass=model.center_of_mass,
        g=model.g,
    )


def test_a_one_row_recording_with_rates_is_refused(excitation, arm, tmp_path):
    """Regression (found by the fuzzer once the rate columns were read): no IndexError."""
    from ftkin.exceptions import InvalidSamples

    table = read_table(excitation)
    short = tmp_path / "one_row.csv"
    write_csv(short, [*table.header, "fx", "fy", "fz", "mx", "my", "mz"], [table.rows[0] + [0] * 6])
    with pytest.raises(InvalidSamples, match="1 row\\(s\\); a moving recording needs at least 3"):
        load_motion_csv(short, arm)
