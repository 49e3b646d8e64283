"""Regenerate docs/images: every image the docs show, made by the code its caption names.

Run: ``make docs-images`` (``PYTHONPATH=. python scripts/docs_images.py [NAME ...]``; needs the
``viz`` and ``plots`` extras and headless Chromium). :data:`IMAGES` maps each file name to the
caption the pages give it (``tests/test_docs_reference.py`` checks the pages against it) and the
function that draws it.
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

IMAGES_DIR = Path(__file__).resolve().parents[1] / "docs" / "images"


def view_png(path: Path, caption: str) -> None:
    """The bundled arm at one pose with a push on the tool (docs/viewer.md's Python block)."""
    import numpy as np

    from ftkin import Arm, calibrate
    from ftkin.calibration.information import SensorNoise
    from ftkin.sim.sensor import SimulatedSensor, paper_like_truth
    from ftkin.viz import CalibrationViewer
    from ftkin.viz.browser import screenshot_html

    rng = np.random.default_rng(7)
    arm = Arm.default()
    sensor = SimulatedSensor(paper_like_truth(), SensorNoise.paper())
    samples = sensor.samples_at_configurations(
        arm, arm.random_configurations(12, rng, margin=0.3), rng, readings_per_pose=100
    )
    calibration = calibrate(samples)
    q = np.array([0.3, 0.2, -0.3, 0.0, 0.2, 0.0])  # rad
    R_BS = arm.rotation_sensor_to_base(q)
    push_in_base = np.array([1.6, 1.2, 2.0])  # N, the environment pushing on the tool
    raw = sensor.read(R_BS, rng, np.r_[R_BS.T @ push_in_base, 0, 0, 0])[0]
    with CalibrationViewer(calibration, arm, tilt_exaggeration=20) as viewer:
        viewer.show_pose(q, raw)
        in_image = caption.split(", ", 1)[-1]  # "a push on the tool"
        screenshot_html(viewer.static_html(caption=in_image), str(path))


def contact_sheet_png(path: Path, caption: str) -> None:
    """``ftkin view --png`` of the bundled arm's 9-pose plan (scripts/contact_sheet_example.py)."""
    import os
    import tempfile

    from ftkin.cli import main as ftkin_main

    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from contact_sheet_example import write_example

    here = os.getcwd()
    with tempfile.TemporaryDirectory() as scratch:
        write_example(Path(scratch))
        os.chdir(scratch)
        try:
            argv = ["view", "calib.json", "samples.csv", "--png", str(path), "--no-wait"]
            if ftkin_main(argv) != 0:
                raise RuntimeError(f"ftkin {' '.join(argv)} failed")
        finally:
            os.chdir(here)


@dataclass(frozen=True)
class Image:
    """An image of the docs: the caption the pages give it and the function that draws it."""

    caption: str
    make: Callable[[Path, str], None]


IMAGES = {
    "view.png": Image("ftkin view: the bundled arm, a push on the tool", view_png),
    "contact_sheet.png": Image(
        "contact sheet of the 9 poses of the bundled arm's plan", contact_sheet_png
    ),
}
"""File name in docs/images → caption and maker."""


def main(argv: list[str]) -> int:
    names = argv or list(IMAGES)
    unknown = [name for name in names if name not in IMAGES]
    if unknown:
        print(f"unknown image(s) {', '.join(unknown)}; known: {', '.join(IMAGES)}", file=sys.stderr)
        return 2
    for name in names:
        image = IMAGES[name]
        image.make(IMAGES_DIR / name, image.caption)
        print(f"wrote docs/images/{name}: {image.caption}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
