"""Every other pose of a 9-pose plan (5 poses), in headless Chromium: the arrows are on screen
and outside the legend.

For the bundled arm and UR5, poses 0, 2, 4, 6 and 8 of ``plan_poses(arm, 9)`` (spread over the
plan, each framed on its own; all nine took 40 s of the suite) are drawn with
simulated readings of a calibrated tool, saved as a static page with the
legend and screenshotted at 1024 × 768 (two Chromium processes at a time).
The measured-force (magenta) and predicted-gravity (cyan) arrows are found
by their colours, counting only pixels outside the legend box; the legend's
own colour swatches are counted inside it, to check that the box is where
the legend is.
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest

import ftkin
from ftkin.sim.sensor import SimulatedSensor, paper_like_truth
from ftkin.viz.browser import find_chromium, screenshot_html
from ftkin.viz.legend import GRAVITY, LEGEND_BOX, MEASURED

pytest.importorskip("meshcat")
image = pytest.importorskip("matplotlib.image")

if find_chromium() is None:
    pytest.skip(
        "headless Chromium not found (install the Debian package chromium: bash "
        "scripts/install-system-deps.sh)",
        allow_module_level=True,
    )

from ftkin.viz import CalibrationViewer  # noqa: E402

SIZE = (1024, 768)
TOLERANCE = 40  # per channel, 0-255
MIN_PIXELS = 150  # an arrow ~25 cm long, a few mm wide, at ~0.8 m: several hundred pixels


def _pages(arm) -> list[tuple[str, object]]:
    plan = ftkin.plan_poses(arm, 9, seed=0)
    rng = np.random.default_rng(1)
    sensor = SimulatedSensor(paper_like_truth(), ftkin.SensorNoise.paper())
    samples = sensor.samples_at_configurations(arm, plan.joint_positions, rng)
    calibration = ftkin.calibrate(samples)
    pages = []
    with CalibrationViewer(calibration, arm) as viewer:
        for k, q in enumerate(plan.joint_positions):
            viewer.show_pose(q, samples.wrenches[k])
            pages.append((viewer.static_html(caption=f"pose {k}"), viewer.view))
    return pages


def _counts(png) -> tuple[int, int, int]:
    pixels = image.imread(str(png))
    rgb = (
        np.round(pixels[..., :3] * 255).astype(np.int16)
        if pixels.dtype != np.uint8
        else pixels[..., :3].astype(np.int16)
    )
    left, top, right, bottom = LEGEND_BOX
    outside = np.ones(rgb.shape[:2], dtype=bool)
    outside[top:bottom, left:right] = False

    def near(color) -> np.ndarray:
        return np.all(np.abs(rgb - np.asarray(color, dtype=np.int16)) <= TOLERANCE, axis=-1)

    measured, gravity = near(MEASURED.rgb), near(GRAVITY.rgb)
    return (
        int((measured & outside).sum()),
        int((gravity & outside).sum()),
        int((measured & ~outside).sum()),
    )


@pytest.mark.parametrize("robot", ["bundled", "ur5"])
def test_arrows_are_visible_outside_the_legend_at_every_pose(robot, tmp_path):
    arm = ftkin.Arm.default() if robot == "bundled" else ftkin.load_robot("ur5")
    pages = _pages(arm)

    def shoot(k: int):
        return _counts(
            screenshot_html(pages[k][0], tmp_path / f"pose{k}.png", window_size=SIZE, timeout=240)
        )

    shown = range(0, len(pages), 2)
    with ThreadPoolExecutor(max_workers=2) as pool:
        counts = list(pool.map(shoot, shown))
    pages = [pages[k] for k in shown]
    print(
        f"\n{robot}: pixels outside the legend per pose (magenta measured / cyan predicted; legend "
        "swatch)"
    )
    for k, (measured, gravity, swatch), (_, view) in zip(shown, counts, pages):
        print(
            f"  pose {k}: measured {measured:5d}  predicted {gravity:5d}  legend swatch "
            f"{swatch:3d}  "
            f"camera offset {np.round(view.offset, 2)} m, floor "
            f"{'shown' if view.floor_visible else 'hidden'}"
        )
    for k, (measured, gravity, swatch) in zip(shown, counts):
        assert measured >= MIN_PIXELS and gravity >= MIN_PIXELS, (robot, k, measured, gravity)
        assert swatch >= 50, (robot, k, "the legend is not inside LEGEND_BOX")
