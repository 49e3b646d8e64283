"""3D view of a calibration in meshcat (optional extra ``viz``).

:class:`CalibrationViewer` draws the arm, the sensor frame and, anchored at
the sensor origin, the measured force, the predicted tool gravity and the
compensated contact force; :mod:`ftkin.viz.browser` renders its static page to a
PNG with headless Chromium, and :mod:`ftkin.viz.report` draws the one-page
calibration report (matplotlib). meshcat is imported only when a viewer is made.

Takes a calibration and samples (or a log); gives pictures. Depends on
:mod:`ftkin.control`, :mod:`ftkin.io` and below.
"""

from .arrows import ArrowPlacement, ArrowStyle, NodePose, arrow_placement, exaggerate_tilt, rotation_y_to
from .legend import ARROWS, LAYERS, Layer
from .vectors import PoseVectors, pose_vectors
from .viewer import CalibrationViewer

__all__ = [
    "ARROWS",
    "ArrowPlacement",
    "ArrowStyle",
    "CalibrationViewer",
    "LAYERS",
    "Layer",
    "NodePose",
    "PoseVectors",
    "arrow_placement",
    "exaggerate_tilt",
    "pose_vectors",
    "rotation_y_to",
]
