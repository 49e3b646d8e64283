"""3D view of a calibration in meshcat (optional extra ``viz``).

:class:`CalibrationViewer` draws the arm, the sensor frame and, anchored at
the sensor origin, the measured force, the predicted tool gravity and the
compensated contact force; :mod:`ftkin.viz.browser` renders its static page to a
PNG with headless Chromium, and :mod:`ftkin.viz.report` draws the one-page
calibration report (matplotlib). :mod:`ftkin.viz.framing` aims the camera at
the sensor at each pose; :mod:`ftkin.viz.contact_sheet` tiles every pose in one
image; :class:`LiveView` draws a running control loop from a separate process.
meshcat is imported only when a viewer is made.

Takes a calibration and samples (or a log); gives pictures. Depends on
:mod:`ftkin.control`, :mod:`ftkin.io` and below.
"""

from .arrows import ArrowPlacement, ArrowStyle, NodePose, arrow_placement, exaggerate_tilt, rotation_y_to
from .framing import PoseView, frame_pose
from .legend import ARROWS, LAYERS, Layer
from .live import LiveView, PublishingController
from .vectors import PoseVectors, pose_vectors
from .viewer import CalibrationViewer

__all__ = [
    "ARROWS",
    "ArrowPlacement",
    "ArrowStyle",
    "CalibrationViewer",
    "LAYERS",
    "Layer",
    "LiveView",
    "NodePose",
    "PoseVectors",
    "PoseView",
    "PublishingController",
    "arrow_placement",
    "exaggerate_tilt",
    "frame_pose",
    "pose_vectors",
    "rotation_y_to",
]
