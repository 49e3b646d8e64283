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

from .._lazy import lazy_exports

_EXPORTS = {
    "ARROWS": ".legend",
    "ArrowPlacement": ".arrows",
    "ArrowStyle": ".arrows",
    "CalibrationViewer": ".viewer",
    "DrawingOptions": ".viewer",
    "LAYERS": ".legend",
    "Layer": ".legend",
    "LiveView": ".live",
    "NodePose": ".arrows",
    "PoseVectors": ".viewer",
    "PoseView": ".framing",
    "PublishingController": ".live",
    "arrow_placement": ".arrows",
    "exaggerate_tilt": ".arrows",
    "frame_pose": ".framing",
    "pose_vectors": ".viewer",
    "rotation_y_to": ".arrows",
}
"""Public name → module, loaded on first access (PEP 562): importing one module of this stage does
not import them all.
"""

__all__ = [
    "ARROWS",
    "ArrowPlacement",
    "ArrowStyle",
    "CalibrationViewer",
    "DrawingOptions",
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

__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS, globals())
