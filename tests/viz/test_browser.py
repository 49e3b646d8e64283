"""The view in a real browser: headless Chromium screenshots meshcat's static page.

The arrows are drawn unlit in saturated colours nothing else in the scene
uses, so each is found by counting the pixels near its colour. At a
calibration pose the thin measured-force arrow lies on the wide predicted-gravity
arrow (each rendered alone, masks compared); with a calibration whose
gravity vector has the wrong sign they do not.
"""

from __future__ import annotations

import numpy as np
import pytest

from ftkin import SensorModel
from ftkin.exceptions import InvalidInput
from ftkin.viz.browser import BrowserError, find_chromium, screenshot_file, screenshot_html
from ftkin.viz.legend import BASE_GRAVITY, CENTER_OF_MASS, CONTACT, GRAVITY, LAYERS, MEASURED

pytest.importorskip("meshcat")
image = pytest.importorskip("matplotlib.image")

if find_chromium() is None:
    pytest.skip(
        "headless Chromium not found (install the Debian package chromium: bash "
        "scripts/install-system-deps.sh)",
        allow_module_level=True,
    )

from ftkin.viz import CalibrationViewer  # noqa: E402

Q_SIDE = np.array(
    [0.3, 0.2, -0.3, 0.0, 0.2, 0.0]
)  # rad: tool roughly horizontal, gravity arrow hangs free
TOLERANCE = 40  # per channel, 0-255
SIZE = (640, 480)


def _read_rgb(path) -> np.ndarray:
    pixels = image.imread(str(path))
    if pixels.dtype != np.uint8:
        pixels = np.round(pixels * 255).astype(np.int16)
    return pixels[..., :3].astype(np.int16)


def _mask(rgb: np.ndarray, color) -> np.ndarray:
    return np.all(np.abs(rgb - np.asarray(color, dtype=np.int16)) <= TOLERANCE, axis=-1)


@pytest.fixture(scope="module")
def viewer(arm):
    with CalibrationViewer(
        SensorModel.from_tool(0.4, [0.0, 0.0, 0.05]), arm
    ) as view:  # calibration replaced per test
        yield view


def _render(viewer, tmp_path, name: str, visible: set[str]) -> np.ndarray:
    for layer in LAYERS:
        viewer.set_visible(layer.name, layer.name in visible)
    png = screenshot_html(
        viewer.static_html(legend=False), tmp_path / f"{name}.png", window_size=SIZE
    )
    return _read_rgb(png)


def _use(viewer, calibration: SensorModel) -> None:
    viewer.set_calibration(calibration)  # same weight, so the same arrow scale


def test_colours_are_not_used_by_the_scene(viewer, tmp_path, arm, truth):
    _use(viewer, truth)
    viewer.show_pose(Q_SIDE, truth.predict(arm.rotation_sensor_to_base(Q_SIDE)))
    rgb = _render(viewer, tmp_path, "none", set())
    counts = {
        layer.name: int(_mask(rgb, layer.rgb).sum())
        for layer in (MEASURED, GRAVITY, CONTACT, CENTER_OF_MASS, BASE_GRAVITY)
    }
    print("pixels near the arrow colours with every arrow hidden:", counts)
    assert max(counts.values()) < 20


def test_every_arrow_is_on_screen_and_gravity_lies_on_the_measured_force(
    viewer, tmp_path, arm, truth
):
    rotation = arm.rotation_sensor_to_base(Q_SIDE)
    _use(viewer, truth)
    push_in_base = np.array(
        [1.6, 1.2, 2.0]
    )  # N: up and to the right on screen, so every arrow points elsewhere
    push = np.concatenate([rotation.T @ push_in_base, np.zeros(3)])
    viewer.show_pose(Q_SIDE, truth.predict(rotation) + push)
    rgb = _render(viewer, tmp_path, "all", {layer.name for layer in LAYERS})
    counts = {
        layer.name: int(_mask(rgb, layer.rgb).sum())
        for layer in (MEASURED, GRAVITY, CONTACT, CENTER_OF_MASS, BASE_GRAVITY)
    }
    print("pixels per colour, all layers, contact (1.6, 1.2, 2.0) N in the base frame:", counts)
    assert counts["center_of_mass"] > 30, counts
    assert min(counts[layer.name] for layer in (MEASURED, GRAVITY, CONTACT, BASE_GRAVITY)) > 100, (
        counts
    )

    # No contact: render the measured and the predicted-gravity arrow alone and compare where they
    # are.
    raw = truth.predict(rotation)
    viewer.show_pose(Q_SIDE, raw)
    measured = _mask(_render(viewer, tmp_path, "measured", {"measured"}), MEASURED.rgb)
    gravity = _mask(_render(viewer, tmp_path, "gravity", {"gravity"}), GRAVITY.rgb)
    # The measured-force needle is thinner than the predicted-gravity sleeve: compare the share of
    # the needle's pixels that lie on the sleeve.
    good = (measured & gravity).sum() / measured.sum()

    wrong = SensorModel(
        truth.force_offset, truth.torque_offset, -truth.gravity_in_base, truth.center_of_mass
    )  # sign flip
    _use(viewer, wrong)
    viewer.auto_camera = (
        False  # keep the camera of the right calibration (framing depends on the predicted gravity)
    )
    try:
        viewer.show_pose(Q_SIDE, raw)
        measured_wrong = _mask(
            _render(viewer, tmp_path, "measured_wrong", {"measured"}), MEASURED.rgb
        )
        gravity_wrong = _mask(_render(viewer, tmp_path, "gravity_wrong", {"gravity"}), GRAVITY.rgb)
    finally:
        viewer.auto_camera = True
    bad = (measured_wrong & gravity_wrong).sum() / measured_wrong.sum()
    print(
        f"measured/gravity pixels: right calibration {measured.sum()}/{gravity.sum()} needle on "
        f"the sleeve {good:.3f}; "
        f"gravity sign flipped {measured_wrong.sum()}/{gravity_wrong.sum()} needle on the sleeve "
        f"{bad:.3f}"
    )
    assert measured.sum() > 150 and gravity.sum() > 150
    assert good > 0.8
    assert bad < 0.1
    # The measured arrow does not depend on the gravity vector: same pixels under both calibrations.
    assert (measured & measured_wrong).sum() / (measured | measured_wrong).sum() > 0.95


def test_screenshot_errors(tmp_path, monkeypatch):
    with pytest.raises(Exception, match="no such file"):
        screenshot_file(tmp_path / "missing.html", tmp_path / "out.png")
    page = tmp_path / "page.html"
    page.write_text("<html><body>hi</body></html>")
    for size in (("wide", 480), (640,), (0, 480)):
        with pytest.raises(InvalidInput, match="two positive pixel counts"):
            screenshot_file(page, tmp_path / "out.png", window_size=size)
    monkeypatch.setenv("FTKIN_CHROMIUM", str(tmp_path / "no-such-browser"))
    with pytest.raises(BrowserError, match="apt-get install chromium"):
        screenshot_file(page, tmp_path / "out.png")
