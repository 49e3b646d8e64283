"""Contact sheet: the cells' angles and outlier flags, the tiled figure, and ``ftkin view --png``
without ``--pose``.

Screenshots are replaced by flat images here (the browser test renders real ones).
"""

from __future__ import annotations

import numpy as np
import pytest

from ftkin import Arm, SensorModel, calibrate, load_calibration, save_calibration
from ftkin.calibration.information import SensorNoise
from ftkin.cli import main
from ftkin.io.csv_table import write_csv
from ftkin.sim.sensor import SimulatedSensor

pytest.importorskip("meshcat")
pytest.importorskip("matplotlib")

from ftkin.viz import (
    CalibrationViewer,  # noqa: E402
    contact_sheet,  # noqa: E402
)
from ftkin.viz.contact_sheet import SheetCell, force_angle_deg, sheet_cells, sheet_figure  # noqa: E402

PUSHED = 3  # pose id that gets a contact during its readings


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("sheet")
    rng = np.random.default_rng(11)
    arm = Arm.default()
    truth = SensorModel.from_tool(
        0.32, [0.002, -0.001, 0.047], [0.4, -0.3, 0.2], [0.01, 0.02, -0.01]
    )
    q = arm.random_configurations(8, rng, margin=0.3)
    samples = SimulatedSensor(truth, SensorNoise.paper()).samples_at_configurations(
        arm, q, rng, readings_per_pose=5
    )
    wrenches = samples.wrenches.copy()
    wrenches[samples.pose_ids == PUSHED, 0] += 1.0  # N
    header = [f"q{i + 1}" for i in range(arm.nq)] + ["fx", "fy", "fz", "mx", "my", "mz", "pose"]
    rows = [
        [*map(float, a), *map(float, w), int(p)]
        for a, w, p in zip(samples.joint_positions, wrenches, samples.pose_ids)
    ]
    write_csv(folder / "samples.csv", header, rows)
    from ftkin import load_samples

    save_calibration(
        calibrate(load_samples(folder / "samples.csv", arm=arm).samples), folder / "calib.json"
    )
    return folder / "calib.json", folder / "samples.csv"


def test_force_angle():
    assert force_angle_deg([1, 0, 0], [0, 2, 0]) == pytest.approx(90.0)
    assert force_angle_deg([1, 0, 0], [1, 1, 0]) == pytest.approx(45.0)
    assert np.isnan(force_angle_deg([0, 0, 0], [1, 0, 0]))


def test_cells_angle_is_between_measured_and_predicted_gravity(arm, truth, rng):
    q = arm.random_configurations(3, rng, margin=0.3)
    rotations = arm.rotation_sensor_to_base(q)
    raws = truth.predict(rotations)
    push = np.array([0.0, 1.1, 0.0])  # N, base frame
    raws[1, :3] += rotations[1].T @ push
    a = truth.gravity_in_base
    expected = np.degrees(
        np.arccos(a @ (a + push) / (np.linalg.norm(a) * np.linalg.norm(a + push)))
    )
    with CalibrationViewer(truth, arm) as viewer:
        cells = sheet_cells(viewer, ["a", "b", "c"], raws, configurations=q, outliers=[1])
    np.testing.assert_allclose([c.angle_deg for c in cells], [0.0, expected, 0.0], atol=1e-6)
    assert expected > 15.0
    assert [c.outlier for c in cells] == [False, True, False]
    assert all(contact_sheet.HIDE_CONTROLS in c.page for c in cells)


def test_figure_tiles_labels_and_outlines_outliers():
    cells = [SheetCell(f"pose {k}", float(k), k == 2, "") for k in range(5)]
    images = [np.full((30, 40, 3), 50 * k, dtype=np.uint8) for k in range(5)]
    figure = sheet_figure(cells, images, "title")
    shown = [ax for ax in figure.axes if ax.images]
    assert len(shown) == 5 and len(figure.axes) == 6  # 3 × 2 grid, one empty
    assert [ax.get_title() for ax in shown][:3] == [
        "pose 0: angle 0.00°",
        "pose 1: angle 1.00°",
        "pose 2: angle 2.00° (outlier)",
    ]
    for k, ax in enumerate(shown):
        np.testing.assert_array_equal(ax.images[0].get_array(), images[k])
        edge = ax.spines["top"].get_edgecolor()
        assert (edge[:3] == (1.0, 0.0, 0.0)) == (k == 2)


def test_view_png_without_pose_writes_a_sheet_of_every_pose(files, tmp_path, monkeypatch, capsys):
    calib, samples = files
    assert load_calibration(calib).diagnostics.outlier_pose_ids == (PUSHED,)
    seen = {}

    def fake_render(
        cells, size=contact_sheet.CELL_SIZE, workers=contact_sheet.WORKERS, timeout=0.0
    ):
        seen["cells"] = list(cells)
        return [np.zeros((size[1], size[0], 3), dtype=np.uint8) for _ in cells]

    monkeypatch.setattr(contact_sheet, "render_cells", fake_render)
    out = tmp_path / "sheet.png"
    assert main(["view", str(calib), str(samples), "--png", str(out), "--no-wait"]) == 0
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    cells = seen["cells"]
    assert [c.label for c in cells] == [f"pose {k}" for k in range(8)]
    assert [c.outlier for c in cells] == [k == PUSHED for k in range(8)]
    assert cells[PUSHED].angle_deg > 2 * max(c.angle_deg for c in cells if not c.outlier)
    assert "contact sheet of 8 poses, 1 outliers" in capsys.readouterr().out
