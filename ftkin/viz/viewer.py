"""A meshcat view of the arm, the sensor frame and the force vectors of a calibration.

:class:`CalibrationViewer` draws, in the base frame B:

* the arm (Pinocchio's ``MeshcatVisualizer``, visual geometry; collision
  geometry loaded hidden), when an :class:`~ftkin.kinematics.arm.Arm` is given;
* the sensor frame triad (x, y, z = red, green, blue);
* arrows anchored at the sensor origin, scaled ``scale`` [m per N]: the
  measured force minus the bias (magenta), the predicted tool gravity (cyan),
  the compensated contact force (yellow) — see :mod:`ftkin.viz.vectors`;
* the tool's centre of mass (green sphere);
* beside the base: the gravity direction the calibration estimates (purple),
  its tilt from the base's −z (dark grey) multiplied by ``tilt_exaggeration``.

At a calibration pose without contact the magenta and cyan arrows lie on top
of each other and the yellow one vanishes.
"""

from __future__ import annotations

import atexit
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..calibration.model import SensorModel
from ..exceptions import InvalidInput
from ..io.atomic import atomic_write_text
from ..kinematics.arm import Arm
from ..validation import as_batch, as_positive, as_vector, from_fields
from .arrows import ArrowStyle, NodePose, arrow_placement, exaggerate_tilt, rigid_transform
from .framing import PoseView, arm_points, frame_pose
from .legend import (
    ARROWS,
    BASE_GRAVITY,
    CENTER_OF_MASS,
    LAYERS,
    VERTICAL,
    add_legend,
    inline_commands,
    legend_html,
)
from .scene import ROOT, add_markers, apply_view, frame_view, set_camera
from .server import import_meshcat, import_pinocchio_visualizer, start_visualizer, stop_server
from .vectors import PoseVectors, pose_vectors

DEFAULT_ARROW_LENGTH = 0.25
"""Drawn length of the tool-weight arrow when no scale is given [m]."""


@dataclass(frozen=True)
class DrawingOptions:
    """How a :class:`CalibrationViewer` draws.

    Attributes:
        scale: Arrow scale [m per N]; None: the tool weight is drawn
            :data:`DEFAULT_ARROW_LENGTH` long.
        tilt_exaggeration: Factor applied to the base tilt angle when drawing
            the gravity direction (1 = true angle).
        style: Arrow sizes [m].
        gravity_anchor: Where the gravity-direction arrow starts (base frame) [m];
            None: beside the sensor, right of it on screen.
        auto_camera: At each pose aim the camera at the sensor origin and see the
            arrows side-on (:func:`ftkin.viz.framing.frame_pose`);
            :meth:`CalibrationViewer.set_camera` turns it off.
    """

    scale: float | None = None
    tilt_exaggeration: float = 1.0
    style: ArrowStyle = field(default_factory=ArrowStyle)
    gravity_anchor: object = None
    auto_camera: bool = True

    def __post_init__(self):
        values = {
            "scale": None if self.scale is None else as_positive(self.scale, "scale [m/N]"),
            "tilt_exaggeration": as_positive(self.tilt_exaggeration, "tilt_exaggeration"),
            "style": self.style or ArrowStyle(),
            "gravity_anchor": None
            if self.gravity_anchor is None
            else as_vector(self.gravity_anchor, 3, "gravity_anchor [m]"),
            "auto_camera": bool(self.auto_camera),
        }
        for name, value in values.items():
            object.__setattr__(self, name, value)


class CalibrationViewer:
    """Show a calibration at poses of an arm in meshcat.

    Args:
        calibration: Calibration (or any :class:`~ftkin.calibration.model.SensorModel`) to show.
        arm: The arm; ``None`` draws the sensor frame at the base origin without an arm.
        zmq_url: Attach to a running meshcat server (``meshcat-server``) instead
            of starting one; an attached server is left running on :meth:`close`.
        visualizer: An existing ``meshcat.Visualizer`` to draw into (left running).
        drawing: How to draw (:class:`DrawingOptions`); or give its fields as keywords
            (``CalibrationViewer(calibration, arm, scale=0.04)``).
    """

    def __init__(
        self,
        calibration: SensorModel,
        arm: Arm | None = None,
        *,
        zmq_url: str | None = None,
        visualizer=None,
        drawing: DrawingOptions | None = None,
        **options,
    ):
        _check_calibration(calibration)
        if arm is not None and not isinstance(arm, Arm):
            raise InvalidInput(f"arm must be an ftkin Arm or None, got {type(arm).__name__}")
        if drawing is not None and options:
            raise InvalidInput("give DrawingOptions or their fields as keywords, not both")
        if drawing is None:
            drawing = from_fields(DrawingOptions, options, "CalibrationViewer")
        self.calibration = calibration
        self.arm = arm
        self.scale = (
            drawing.scale
            if drawing.scale is not None
            else DEFAULT_ARROW_LENGTH / max(calibration.tool_weight, 1e-9)
        )
        self.tilt_exaggeration, self.style = drawing.tilt_exaggeration, drawing.style
        self.gravity_anchor, self.auto_camera = drawing.gravity_anchor, drawing.auto_camera
        self.view: PoseView | None = None
        self._anchor = (
            np.array([-0.25, -0.3, 0.4]),
            0.3,
        )  # gravity arrow beside the base until a pose is framed
        self._meshcat = import_meshcat()
        self._owns_server = visualizer is None and zmq_url is None
        self.visualizer = visualizer if visualizer is not None else start_visualizer(zmq_url)
        self._closed = False
        self._robot = None
        self._animation = None
        atexit.register(self.close)
        try:
            self._build_scene()
        except BaseException:
            self.close()
            raise

    # ------------------------------------------------------------- lifecycle
    @property
    def url(self) -> str:
        """Web address of the live viewer."""
        return self.visualizer.url()

    @property
    def server_process(self):
        """The meshcat server subprocess this viewer started, or None."""
        return getattr(self.visualizer.window, "server_proc", None) if self._owns_server else None

    def close(self) -> None:
        """Stop the server this viewer started (kill and wait); idempotent."""
        if self._closed:
            return
        self._closed = True
        atexit.unregister(self.close)
        if self._owns_server:
            stop_server(self.visualizer)

    def __enter__(self) -> CalibrationViewer:
        return self

    def __exit__(self, *exc_info) -> None:
        self.close()

    # ----------------------------------------------------------------- scene
    def _build_scene(self) -> None:
        if self.arm is not None:
            visualizer_class = import_pinocchio_visualizer()
            self._robot = visualizer_class(
                self.arm.model, self.arm.geometry("collision"), self.arm.geometry("visual")
            )
            self._robot.initViewer(viewer=self.visualizer)
            self._robot.loadViewerModel(rootNodeName="pinocchio")
        add_markers(self.visualizer, self._meshcat.geometry, self.style)
        frame_view(self.visualizer, self._meshcat.geometry, self.arm)

    def set_calibration(self, calibration: SensorModel) -> None:
        """Show another calibration from the next pose on (the arrow scale stays)."""
        _check_calibration(calibration)
        self.calibration = calibration

    def set_camera(self, position) -> None:
        """Camera position relative to the orbit target, base axes [m]; stops the per-pose
        framing.
        """
        self.auto_camera = False
        set_camera(self.visualizer, position)

    def set_visible(self, name: str, visible: bool) -> None:
        """Show or hide a layer (``measured``, ``gravity``, ``contact``, ``center_of_mass``,
        ``base_gravity``, ``vertical``, ``sensor``, ``arm``)."""
        names = [layer.name for layer in LAYERS] + ["sensor", "arm"]
        if name not in names:
            raise InvalidInput(f"unknown layer {name!r}; layers: {', '.join(names)}")
        path = "pinocchio" if name == "arm" else f"{ROOT}/{name}"
        self.visualizer[path].set_property("visible", bool(visible))

    # ----------------------------------------------------------------- poses
    def show_pose(self, q, raw_wrench) -> PoseVectors:
        """Draw the arm at joint angles ``q`` [rad] with the vectors of one raw reading [N, N·m]."""
        return self._draw(self.visualizer, q, None, raw_wrench, animated=False)

    def show_rotation(
        self, rotation_sensor_to_base, raw_wrench, sensor_origin=(0.0, 0.0, 0.0)
    ) -> PoseVectors:
        """Draw the vectors for an orientation ``R_BS`` without joint angles (sensor at
        ``sensor_origin`` [m]).
        """
        return self._draw(
            self.visualizer,
            None,
            (rotation_sensor_to_base, sensor_origin),
            raw_wrench,
            animated=False,
        )

    def animate(
        self,
        raw_wrenches,
        *,
        configurations=None,
        rotations=None,
        times=None,
        hold: float = 1.0,
        fps: int = 30,
        repetitions: int = 1000,
        play: bool = True,
    ) -> list[PoseVectors]:
        """Store a meshcat animation through several poses (kept in :meth:`static_html`).

        Args:
            raw_wrenches: ``(N, 6)`` raw readings [N, N·m].
            configurations: ``(N, nq)`` joint angles [rad] (needs an arm), or
            rotations: ``(N, 3, 3)`` ``R_BS`` (sensor drawn at the base origin).
            times: ``(N,)`` increasing times [s] (a recorded run); default:
                each pose held ``hold`` seconds (calibration poses).
            fps: Animation frame rate [1/s].
            repetitions: How many times the page plays it.
        """
        raw, _ = as_batch(raw_wrenches, 6, "raw wrenches")
        count = len(raw)
        if (configurations is None) == (rotations is None):
            raise InvalidInput("give exactly one of configurations= (joint angles) or rotations=")
        if times is None:
            step = max(int(round(as_positive(hold, "hold [s]") * fps)), 1)
            starts = np.arange(count) * step
            frames = [(int(s), int(s + step - 1)) for s in starts]
        else:
            times = np.asarray(times, dtype=float).reshape(-1)
            if (
                times.shape != (count,)
                or not np.all(np.isfinite(times))
                or np.any(np.diff(times) < 0)
            ):
                raise InvalidInput(f"times must be {count} finite non-decreasing values [s]")
            frames = [(int(round(f)),) for f in (times - times[0]) * fps]
        animation = self._meshcat.animation.Animation(default_framerate=fps)
        out = []
        for k in range(count):
            for frame in frames[k]:
                sink = animation.at_frame(self.visualizer, frame)
                if configurations is not None:
                    vectors = self._draw(sink, configurations[k], None, raw[k], animated=True)
                else:
                    vectors = self._draw(
                        sink, None, (rotations[k], (0.0, 0.0, 0.0)), raw[k], animated=True
                    )
            out.append(vectors)
        self.visualizer.set_animation(animation, play=play, repetitions=repetitions)
        self._animation = animation
        return out

    def _draw(self, sink, q, rotation_and_origin, raw_wrench, animated: bool) -> PoseVectors:
        """Draw one reading into ``sink`` (the viewer, or an animation frame): the arm at ``q``
        or the sensor at ``(R_BS, origin)``, the force arrows, the COM, the gravity direction.
        """
        if q is not None:
            rotation, origin, points = self._draw_arm(sink, q)
        else:
            (rotation, origin), points = rotation_and_origin, None
        vectors = pose_vectors(self.calibration, rotation, origin, raw_wrench)
        origin, place = vectors.sensor_origin, _place_animated if animated else _place_live
        sensor = rigid_transform(vectors.rotation_sensor_to_base, vectors.sensor_origin)
        place(sink, f"{ROOT}/sensor", NodePose(sensor, np.ones(3)))
        forces = (vectors.measured_force, vectors.gravity_force, vectors.contact_force)
        for layer, force in zip(ARROWS, forces):
            _place_arrow(place, sink, layer, arrow_placement(origin, force, self.scale, self.style))
        com = NodePose(rigid_transform(np.eye(3), vectors.center_of_mass), np.ones(3))
        place(sink, f"{ROOT}/{CENTER_OF_MASS.name}", com)
        if self.auto_camera:
            tool_size = 2.0 * float(np.linalg.norm(self.calibration.center_of_mass))
            self.view = frame_pose(
                origin, [self.scale * f for f in forces], points, tool_size=tool_size
            )
            apply_view(sink, self.view, animated)
            if self.gravity_anchor is None:  # beside the sensor, right of it, a little up
                view = self.view
                anchor = view.target + view.radius * (0.8 * view.right + np.array([0, 0, 0.3]))
                self._anchor = (anchor, min(0.3, 0.6 * view.radius))
        anchor, length = self._anchor if self.gravity_anchor is None else (self.gravity_anchor, 0.3)
        drawn_direction = exaggerate_tilt(vectors.gravity_direction, self.tilt_exaggeration)
        for layer, direction in ((BASE_GRAVITY, drawn_direction), (VERTICAL, (0.0, 0.0, -1.0))):
            _place_arrow(place, sink, layer, arrow_placement(anchor, direction, length, self.style))
        return vectors

    def _draw_arm(self, sink, q):
        """The arm drawn at ``q`` [rad]; returns the sensor's ``R_BS``, origin [m] and the arm's
        points for the camera (None without auto camera).
        """
        if self.arm is None:
            raise InvalidInput(
                "this viewer has no arm: use show_rotation(R_BS, raw_wrench) or pass arm="
            )
        q = self.arm.check_configuration(q)
        rotation, origin = self.arm.frame_placement(q, "sensor")
        if self._robot is not None:
            self._robot.viewer = sink
            try:
                self._robot.display(q)
            finally:
                self._robot.viewer = self.visualizer
        return rotation, origin, arm_points(self.arm, q) if self.auto_camera else None

    # ---------------------------------------------------------------- export
    def legend(self, caption: str = "") -> str:
        """The HTML legend: colours, scale [cm per N] and the estimated tilt."""
        return legend_html(
            self.scale, self.calibration.base_tilt_deg, self.tilt_exaggeration, caption
        )

    def static_html(self, legend: bool = True, caption: str = "") -> str:
        """A self-contained page of the current scene (and animation), optionally with the
        legend.
        """
        page = inline_commands(self.visualizer.static_html())
        return add_legend(page, self.legend(caption)) if legend else page

    def save_html(self, path, legend: bool = True, caption: str = "") -> Path:
        """Write :meth:`static_html` to ``path`` atomically; returns the path."""
        return atomic_write_text(path, self.static_html(legend, caption))


def _check_calibration(calibration) -> None:
    if not isinstance(calibration, SensorModel):
        raise InvalidInput(
            "calibration must be an ftkin SensorModel or CalibrationResult, got "
            f"{type(calibration).__name__}"
        )


def _place_arrow(place, sink, layer, arrow) -> None:
    place(sink, f"{ROOT}/{layer.name}/shaft", arrow.shaft)
    place(sink, f"{ROOT}/{layer.name}/head", arrow.head)


def _place_live(sink, path: str, pose: NodePose) -> None:
    sink[path].set_transform(pose.matrix())


def _place_animated(sink, path: str, pose: NodePose) -> None:
    node = sink[path]
    node.set_transform(pose.rigid)
    node.set_property("scale", "vector3", [float(v) for v in pose.scale])
