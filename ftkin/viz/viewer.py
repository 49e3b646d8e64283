"""A meshcat view of the arm, the sensor frame and the force vectors of a calibration.

:class:`CalibrationViewer` draws, in the base frame B:

* the arm (Pinocchio's ``MeshcatVisualizer``, visual geometry; collision
  geometry loaded hidden), when an :class:`~ftkin.kinematics.arm.Arm` is given;
* the sensor frame triad (x, y, z = red, green, blue);
* arrows anchored at the sensor origin, scaled ``scale`` [m per N]
  (:func:`pose_vectors`):

  * ``measured`` (magenta): ``R_BS (F - F0)`` [N], the raw force with the bias removed;
  * ``gravity`` (cyan): ``R_BS Gs = a`` [N], the predicted tool weight;
  * ``contact`` (yellow): ``R_BS F'`` [N], ``F' = F - F0 - Gs`` (the compensated force, from
    the model's :meth:`~ftkin.calibration.model.SensorModel.predict`);

* the tool's centre of mass ``p_S + R_BS P`` [m] (green sphere);
* beside the sensor: the gravity direction the calibration estimates (the unit
  direction of ``a``, purple), its tilt from the base's −z (dark grey)
  multiplied by ``tilt_exaggeration``.

At a static calibration pose without contact the measured force minus the
bias equals the tool weight the calibration predicts: the magenta and cyan
arrows lie on top of each other and the yellow one vanishes.

meshcat 0.3.2 cannot move the camera's orbit target, so the whole scene
(``/meshcat``, ``/Axes``) is shifted to put the target at the origin, and the
camera is placed through ``/Cameras/default/rotated/<object>`` (three.js axes:
``[x, z, -y]``). meshcat's grid does not follow a transform; it is hidden and
a translucent floor plate is drawn under the arm instead.
"""

import atexit
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..calibration.model import SensorModel
from ..exceptions import InvalidInput
from ..io.atomic import atomic_write_text
from ..kinematics.arm import Arm
from ..validation import as_batch, as_positive, as_rotation_batch, as_vector, from_fields
from .arrows import (
    ArrowStyle,
    NodePose,
    add_arrow_objects,
    arrow_placement,
    exaggerate_tilt,
    rigid_transform,
)
from .framing import PoseView, arm_points, frame_pose
from .legend import (
    ARROWS,
    BASE_GRAVITY,
    CENTER_OF_MASS,
    GRAVITY,
    LAYERS,
    MEASURED,
    VERTICAL,
    add_legend,
    inline_commands,
    legend_html,
)
from .server import import_meshcat, load_arm, start_visualizer, stop_server

DEFAULT_ARROW_LENGTH = 0.25
"""Drawn length of the tool-weight arrow when no scale is given [m]."""

ROOT = "ftkin"
"""Scene folder of everything ftkin draws besides the arm."""

CAMERA_PATH = "/Cameras/default/rotated/<object>"
"""meshcat's camera object (three.js axes ``[x, z, -y]``, y up)."""

RADIUS_FACTORS = {MEASURED.name: 0.5, GRAVITY.name: 1.6, VERTICAL.name: 0.5}
"""Arrow radii relative to the style: a thin measured-force needle inside a wide predicted-gravity
sleeve.
"""

CAMERA_DIRECTION = np.array([0.55, -0.75, 0.35]) / np.linalg.norm([0.55, -0.75, 0.35])
"""From the orbit target towards the camera (base axes): front right, above."""


@dataclass(frozen=True)
class PoseVectors:
    """Everything drawn for one pose (base frame B).

    Attributes:
        rotation_sensor_to_base: ``R_BS`` ``(3, 3)``.
        sensor_origin: Sensor origin in the base frame [m].
        measured_force: ``R_BS (F - F0)`` [N].
        gravity_force: Predicted tool weight ``a`` [N].
        contact_force: ``R_BS F'`` [N], the compensated contact force.
        contact_wrench: ``F'`` and ``M'`` in the sensor frame [N, N·m].
        center_of_mass: Tool centre of mass in the base frame [m].
        gravity_direction: Unit vector along ``a`` (base frame).
    """

    rotation_sensor_to_base: np.ndarray
    sensor_origin: np.ndarray
    measured_force: np.ndarray
    gravity_force: np.ndarray
    contact_force: np.ndarray
    contact_wrench: np.ndarray
    center_of_mass: np.ndarray
    gravity_direction: np.ndarray


def pose_vectors(
    calibration: SensorModel, rotation_sensor_to_base, sensor_origin, raw_wrench
) -> PoseVectors:
    """Compute the drawn vectors of one pose (pure numpy).

    Args:
        calibration: The calibration to check (bias, tool weight, COM).
        rotation_sensor_to_base: ``R_BS`` ``(3, 3)`` at this pose.
        sensor_origin: Sensor origin in the base frame [m] (zero without an arm).
        raw_wrench: Raw reading ``[fx, fy, fz, mx, my, mz]`` [N, N·m] of the real sensor
            (its reading signs applied: :func:`~ftkin.calibration.conventions.as_real_sensor`).
    """
    rotations, _ = as_rotation_batch(rotation_sensor_to_base)
    if len(rotations) != 1:
        raise InvalidInput("pose_vectors takes one (3, 3) rotation, got a batch")
    rotation = rotations[0]
    origin = as_vector(sensor_origin, 3, "sensor origin")
    raw = as_vector(raw_wrench, 6, "raw wrench [fx, fy, fz, mx, my, mz]")
    contact = raw - calibration.predict(rotation)  # F' = F − F0 − Gs, M' = M − M0 − P × Gs
    gravity = np.array(calibration.gravity_in_base, dtype=float)
    weight = np.linalg.norm(gravity)
    return PoseVectors(
        rotation_sensor_to_base=rotation,
        sensor_origin=origin,
        measured_force=rotation @ (raw[:3] - calibration.force_offset),
        gravity_force=gravity,
        contact_force=rotation @ contact[:3],
        contact_wrench=contact,
        center_of_mass=origin + rotation @ calibration.center_of_mass,
        gravity_direction=gravity / weight if weight > 0 else np.array([0.0, 0.0, -1.0]),
    )


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
        self.calibration = _checked(calibration)
        if arm is not None and not isinstance(arm, Arm):
            raise InvalidInput(f"arm must be an ftkin Arm or None, got {type(arm).__name__}")
        if drawing is not None and options:
            raise InvalidInput("give DrawingOptions or their fields as keywords, not both")
        drawing = drawing or from_fields(DrawingOptions, options, "CalibrationViewer")
        self.arm = arm
        self.scale = drawing.scale or DEFAULT_ARROW_LENGTH / max(calibration.tool_weight, 1e-9)
        self.tilt_exaggeration, self.style = drawing.tilt_exaggeration, drawing.style
        self.gravity_anchor, self.auto_camera = drawing.gravity_anchor, drawing.auto_camera
        self.view: PoseView | None = None
        # Start [m] and length [m] of the gravity-direction arrow: beside the base until a pose
        # is framed.
        anchor = (
            np.array([-0.25, -0.3, 0.4]) if self.gravity_anchor is None else self.gravity_anchor
        )
        self._anchor = (anchor, 0.3)
        self._meshcat = import_meshcat()
        self._owns_server = visualizer is None and zmq_url is None
        self.visualizer = visualizer if visualizer is not None else start_visualizer(zmq_url)
        self._closed = False
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

    def __enter__(self) -> "CalibrationViewer":
        return self

    def __exit__(self, *exc_info) -> None:
        self.close()

    # ----------------------------------------------------------------- scene
    def _build_scene(self) -> None:
        """The arm, the markers (sensor triad; arrows: unit shaft + cone head, unlit; the COM
        sphere), the floor, and the camera on the arm's frame origins at ``q = 0`` (clipped to the
        limits).
        """
        geometry, arm = self._meshcat.geometry, self.arm
        self._robot = None if arm is None else load_arm(arm, self.visualizer)
        self.visualizer[f"{ROOT}/sensor"].set_object(geometry.triad(0.12))
        for layer in (*ARROWS, BASE_GRAVITY, VERTICAL):
            # The predicted-gravity arrow shows only its inner faces (THREE.BackSide = 1, else
            # DoubleSide = 2): unlit it looks the same, but the measured-force needle inside it
            # stays visible when the two coincide (a good calibration).
            material = geometry.MeshBasicMaterial(
                color=layer.color, side=1 if layer is GRAVITY else 2
            )
            node = self.visualizer[f"{ROOT}/{layer.name}"]
            add_arrow_objects(
                node, geometry, self.style, material, RADIUS_FACTORS.get(layer.name, 1)
            )
        self.visualizer[f"{ROOT}/{CENTER_OF_MASS.name}"].set_object(
            geometry.Sphere(0.7 * self.style.head_radius),
            geometry.MeshBasicMaterial(color=CENTER_OF_MASS.color, depthTest=False),  # seen through
        )
        if arm is None:
            target, extent = np.zeros(3), 0.6
        else:
            q = np.clip(np.zeros(arm.nq), arm.lower_limits, arm.upper_limits)
            origins = np.array([arm.frame_placement(q, name)[1] for name in arm.frame_names])
            target = 0.5 * (origins.min(axis=0) + origins.max(axis=0))
            extent = max(float(np.ptp(origins, axis=0).max()), 0.5)
        self.visualizer["/Grid"].set_property("visible", False)
        floor = self.visualizer[f"{ROOT}/floor"]  # translucent: the arm may reach below
        floor.set_object(
            geometry.Box([2.0 * extent, 2.0 * extent, 0.004]),
            geometry.MeshLambertMaterial(color=0xD8D8D8, transparent=True, opacity=0.45),
        )
        floor.set_transform(rigid_transform(np.eye(3), [target[0], target[1], -0.003]))
        view = PoseView(target, 1.25 * extent * CAMERA_DIRECTION, True, extent, 0.0)
        _apply_view(self.visualizer, view, animated=False)

    def set_calibration(self, calibration: SensorModel) -> None:
        """Show another calibration from the next pose on (the arrow scale stays)."""
        self.calibration = _checked(calibration)

    def set_camera(self, position) -> None:
        """Camera position relative to the orbit target, base axes [m]; stops the per-pose
        framing.
        """
        self.auto_camera = False
        x, y, z = as_vector(position, 3, "camera position [m]")
        self.visualizer[CAMERA_PATH].set_property("position", [float(x), float(z), float(-y)])

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
        return self._draw(self.visualizer, raw_wrench, animated=False, q=q)

    def show_rotation(
        self, rotation_sensor_to_base, raw_wrench, sensor_origin=(0.0, 0.0, 0.0)
    ) -> PoseVectors:
        """Draw the vectors for an orientation ``R_BS`` without joint angles (sensor at
        ``sensor_origin`` [m]).
        """
        return self._draw(
            self.visualizer,
            raw_wrench,
            animated=False,
            rotation=rotation_sensor_to_base,
            origin=sensor_origin,
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
        if (configurations is None) == (rotations is None):
            raise InvalidInput("give exactly one of configurations= (joint angles) or rotations=")
        if times is None:  # each pose's first and last frame
            step = max(int(round(as_positive(hold, "hold [s]") * fps)), 1)
            frames = [(k * step, k * step + step - 1) for k in range(len(raw))]
        else:
            times = np.asarray(times, dtype=float).reshape(-1)
            if (
                times.shape != (len(raw),)
                or not np.all(np.isfinite(times))
                or np.any(np.diff(times) < 0)
            ):
                raise InvalidInput(f"times must be {len(raw)} finite non-decreasing values [s]")
            frames = [(int(round(f)),) for f in (times - times[0]) * fps]
        animation = self._meshcat.animation.Animation(default_framerate=fps)
        out = []
        for k, pose_frames in enumerate(frames):
            pose = {"q": configurations[k]} if rotations is None else {"rotation": rotations[k]}
            for frame in pose_frames:
                sink = animation.at_frame(self.visualizer, frame)
                vectors = self._draw(sink, raw[k], animated=True, **pose)
            out.append(vectors)
        self.visualizer.set_animation(animation, play=play, repetitions=repetitions)
        return out

    def _draw(
        self, sink, raw_wrench, animated: bool, q=None, rotation=None, origin=(0.0, 0.0, 0.0)
    ) -> PoseVectors:
        """Draw one reading into ``sink`` (the viewer, or an animation frame): the arm at ``q``
        [rad] or the sensor at ``rotation`` (``R_BS``) and ``origin`` [m], the force arrows, the
        COM, the gravity direction.
        """
        points = None  # the arm's, for the camera
        if q is not None:
            if self.arm is None:
                raise InvalidInput(
                    "this viewer has no arm: use show_rotation(R_BS, raw_wrench) or pass arm="
                )
            q = self.arm.check_configuration(q)
            rotation, origin = self.arm.frame_placement(q, "sensor")
            self._robot.viewer = sink
            try:
                self._robot.display(q)
            finally:
                self._robot.viewer = self.visualizer
            points = arm_points(self.arm, q) if self.auto_camera else None
        vectors = pose_vectors(self.calibration, rotation, origin, raw_wrench)
        origin = vectors.sensor_origin
        forces = (vectors.measured_force, vectors.gravity_force, vectors.contact_force)
        if self.auto_camera:
            tool_size = 2.0 * float(np.linalg.norm(self.calibration.center_of_mass))
            view = frame_pose(origin, [self.scale * f for f in forces], points, tool_size=tool_size)
            _apply_view(sink, view, animated)
            self.view = view
            if self.gravity_anchor is None:  # beside the sensor, right of it, a little up
                anchor = view.target + view.radius * (0.8 * view.right + np.array([0, 0, 0.3]))
                self._anchor = (anchor, min(0.3, 0.6 * view.radius))
        anchor, length = self._anchor
        tilted = exaggerate_tilt(vectors.gravity_direction, self.tilt_exaggeration)
        arrows = [(layer, origin, force, self.scale) for layer, force in zip(ARROWS, forces)]
        arrows += [(BASE_GRAVITY, anchor, tilted, length), (VERTICAL, anchor, (0, 0, -1.0), length)]
        nodes = {
            "sensor": NodePose(
                rigid_transform(vectors.rotation_sensor_to_base, origin), np.ones(3)
            ),
            CENTER_OF_MASS.name: NodePose(
                rigid_transform(np.eye(3), vectors.center_of_mass), np.ones(3)
            ),
        }
        for layer, start, vector, scale in arrows:
            arrow = arrow_placement(start, vector, scale, self.style)
            nodes[f"{layer.name}/shaft"], nodes[f"{layer.name}/head"] = arrow.shaft, arrow.head
        for name, pose in nodes.items():
            # meshcat's animation frames record no scale in set_transform: it is sent apart
            sink[f"{ROOT}/{name}"].set_transform(pose.rigid if animated else pose.matrix())
            if animated:
                sink[f"{ROOT}/{name}"].set_property("scale", "vector3", pose.scale.tolist())
        return vectors

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


def _checked(calibration) -> SensorModel:
    if not isinstance(calibration, SensorModel):
        raise InvalidInput(
            "calibration must be an ftkin SensorModel or CalibrationResult, got "
            f"{type(calibration).__name__}"
        )
    return calibration


def _apply_view(sink, view: PoseView, animated: bool) -> None:
    """Aim the camera of ``sink`` (the viewer or an animation frame) at ``view.target``: the scene
    shifted by ``-target``, the camera at ``view.offset``, the floor shown only when it cannot
    hide an arrow.
    """
    shift = rigid_transform(np.eye(3), -view.target)
    sink["/meshcat"].set_transform(shift)
    sink["/Axes"].set_transform(shift)
    x, y, z = (float(v) for v in view.offset)
    properties = (
        (CAMERA_PATH, "position", "vector3", [x, z, -y]),
        (f"/meshcat/{ROOT}/floor", "visible", "boolean", bool(view.floor_visible)),
    )
    for path, key, kind, value in properties:  # an animation frame also records the kind
        if animated:
            sink[path].set_property(key, kind, value)
        else:
            sink[path].set_property(key, value)
