"""What the robot controller must be told: the measured load minus what it already models.

A wrist sensor weighs everything below its measuring plane: the end effector (e.g. the Franka
Hand) and the tool. A robot controller already models the end effector configured on it
(libfranka reports it as ``m_ee``, ``F_x_Cee``, ``I_ee``) and adds the load it is given
(``set_load``). The sensor's own body, between the flange and the measuring plane, is seen by
neither the sensor nor, usually, the controller. So the load to send is, as rigid-body inertias
in the flange frame F (Pinocchio's ``pin.Inertia``: mass, centre of mass, inertia about it)::

    Y_load = Y_measured − Y_end_effector + Y_sensor_body

Every body then appears exactly once in the controller's model. Counted twice (the hand in the
end-effector setting and in the load) or missing (the sensor body), the controller's gravity
model is wrong by that weight, and an arm under velocity or torque control drifts.

A static calibration does not see rotational inertia: when the measured inertia is unknown,
the difference ``Y_measured − Y_end_effector`` is sent as a point mass at its centre of mass.

The load itself (:class:`Payload`) and the check of a rotational inertia
(:func:`checked_inertia`) live here, below the export formats of
:mod:`ftkin.io.payload_export` that write them.
"""

from dataclasses import dataclass, replace

import numpy as np
import pinocchio as pin

from ..calibration.log_cholesky import is_physically_consistent, parameters_from_body
from ..exceptions import InvalidInput, NonPhysicalPayload
from ..validation import as_float_array, as_vector

MASS_TOLERANCE = 1e-4
"""Masses within this of zero are zero [kg] (float32 round trips, calibration noise)."""
MAX_COM_DISTANCE = 1.0
"""A load's centre of mass farther than this from the flange origin is refused [m]."""
END_EFFECTOR_SETTING = "the robot's end-effector setting (libfranka m_ee, F_x_Cee, I_ee)"


@dataclass(frozen=True)
class Payload:
    """The tool as a robot controller's payload.

    Attributes:
        mass: Tool mass [kg].
        center_of_mass: Centre of mass in the flange frame [m].
        flange_frame: Name of that frame in the URDF.
        inertia: ``(3, 3)`` inertia about the centre of mass, flange axes [kg·m²], or None
            (unknown).
    """

    mass: float
    center_of_mass: np.ndarray
    flange_frame: str
    inertia: np.ndarray | None = None


def checked_inertia(value) -> np.ndarray | None:
    """A rotational inertia [kg·m²] as a symmetric positive semidefinite ``(3, 3)`` matrix, from
    a ``(3, 3)`` matrix or ``[ixx, iyy, izz, ixy, ixz, iyz]``; None stays None.

    Raises:
        InvalidInput: another shape, not finite, not symmetric, or a negative principal moment.
    """
    if value is None:
        return None
    array = as_float_array(value, "inertia [kg·m²]")
    if array.shape == (6,):
        ixx, iyy, izz, ixy, ixz, iyz = array
        array = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
    if array.shape != (3, 3) or not np.all(np.isfinite(array)) or not np.allclose(array, array.T):
        raise InvalidInput(
            "inertia must be a symmetric (3, 3) matrix or [ixx, iyy, izz, ixy, ixz, iyz] [kg·m²], "
            f"got {value!r}"
        )
    array = 0.5 * (array + array.T)
    moments = np.linalg.eigvalsh(array)
    tolerance = 1e-9 * max(1.0, float(np.abs(array).max()))
    if moments[0] < -tolerance:
        raise InvalidInput(
            f"inertia must be positive semidefinite, got principal moments {moments.tolist()} kg·m²"
        )
    # a body has it when its pseudo-inertia is (the calibration's own test; the COM's own
    # inertia is independent of the mass and the COM, so a unit point mass at the origin)
    if not is_physically_consistent(parameters_from_body(1.0, np.zeros(3), array), -tolerance):
        raise InvalidInput(
            f"inertia's principal moments {moments.tolist()} kg·m² break the triangle inequality "
            "(the largest must not exceed the sum of the other two): no rigid body has them"
        )
    return array


@dataclass(frozen=True)
class RigidBody:
    """A rigid body's inertia in the flange frame.

    Attributes:
        mass: Mass [kg] (≥ 0).
        center_of_mass: ``(3,)`` centre of mass in the flange frame [m].
        inertia: ``(3, 3)`` rotational inertia about the centre of mass, flange axes [kg·m²].
    """

    mass: float
    center_of_mass: np.ndarray
    inertia: np.ndarray

    def __post_init__(self):
        mass = float(self.mass)
        if not np.isfinite(mass) or mass < 0.0:
            raise InvalidInput(f"a body's mass must be finite and >= 0 kg, got {self.mass!r}")
        com = as_vector(self.center_of_mass, 3, "centre of mass [m]")
        inertia = checked_inertia(self.inertia)
        for array in (com, inertia):
            array.setflags(write=False)
        object.__setattr__(self, "mass", mass)
        object.__setattr__(self, "center_of_mass", com)
        object.__setattr__(self, "inertia", inertia)

    @classmethod
    def point(cls, mass: float, center_of_mass) -> "RigidBody":
        """A point mass [kg] at ``center_of_mass`` [m, flange frame]."""
        return cls(mass, center_of_mass, np.zeros((3, 3)))

    @classmethod
    def from_franka(cls, mass: float, com, inertia_column_major) -> "RigidBody":
        """From libfranka's ``m``, ``F_x_C`` (3,) and ``I`` (9,) column-major (``m_ee``, ...)."""
        inertia = np.asarray(inertia_column_major, dtype=float).reshape(-1)
        if inertia.shape != (9,):
            raise InvalidInput(f"expected a 9-element inertia, got shape {inertia.shape}")
        matrix = inertia.reshape(3, 3, order="F")
        return cls(float(mass), np.asarray(com, dtype=float), 0.5 * (matrix + matrix.T))

    def to_pin(self) -> pin.Inertia:
        """The body as a ``pin.Inertia`` (flange frame)."""
        return pin.Inertia(self.mass, self.center_of_mass.copy(), self.inertia.copy())

    def franka_inertia(self) -> list[float]:
        """The inertia as libfranka's 9 numbers, column-major [kg·m²]."""
        return [float(v) for v in self.inertia.reshape(-1, order="F")]


def controller_load(
    measured: Payload,
    end_effector: RigidBody | None = None,
    sensor_body: RigidBody | None = None,
    *,
    setting: str = END_EFFECTOR_SETTING,
) -> Payload:
    """The load for the controller: ``measured − end_effector + sensor_body`` (flange frame).

    Args:
        measured: What the calibration measured below the sensor, in the flange frame
            (:func:`~ftkin.io.payload_export.payload_in_flange`).
        end_effector: The body the controller already models (None: nothing).
        sensor_body: The sensor's own body above its measuring plane (datasheet mass and centre
            of mass; None: nothing).
        setting: How to name the end-effector setting in an error message.

    Returns:
        A :class:`Payload` in the measured payload's flange frame; its ``inertia`` is None when
        the measured inertia is unknown and no sensor body is added (a point mass).

    Raises:
        NonPhysicalPayload: the difference has a negative mass, a first moment without mass, a
            centre of mass beyond :data:`MAX_COM_DISTANCE`, or an inertia that is not positive
            semidefinite; the message names ``setting``.
    """
    if not isinstance(measured, Payload):
        raise InvalidInput(f"measured must be an ftkin Payload, got {type(measured).__name__}")
    for name, body in (("end_effector", end_effector), ("sensor_body", sensor_body)):
        if body is not None and not isinstance(body, RigidBody):
            raise InvalidInput(f"{name} must be an ftkin RigidBody or None, got {body!r}")
    remainder = _difference(measured, end_effector, setting)
    total = remainder if sensor_body is None else remainder + sensor_body.to_pin()
    inertia_known = measured.inertia is not None or (
        sensor_body is not None and np.any(sensor_body.inertia)
    )
    mass = float(total.mass)
    com = np.array(total.lever) if mass > 0.0 else np.zeros(3)
    inertia = _symmetric(np.array(total.inertia)) if inertia_known else None
    return replace(measured, mass=mass, center_of_mass=com, inertia=inertia)


def _difference(measured: Payload, end_effector: RigidBody | None, setting: str) -> pin.Inertia:
    """``Y_measured − Y_end_effector``, checked to be a body (a point mass without inertias)."""
    inertia = np.zeros((3, 3)) if measured.inertia is None else measured.inertia
    body = RigidBody(measured.mass, measured.center_of_mass, inertia)  # a point mass if unknown
    if end_effector is None:
        return body.to_pin()
    mass = body.mass - end_effector.mass
    moment = body.mass * body.center_of_mass - end_effector.mass * end_effector.center_of_mass
    described = (
        f"the calibration measured {body.mass:.4g} kg below the sensor, centre of mass "
        f"{np.round(body.center_of_mass, 4).tolist()} m (flange frame); {setting} is "
        f"{end_effector.mass:.4g} kg at {np.round(end_effector.center_of_mass, 4).tolist()} m"
    )
    if mass < -MASS_TOLERANCE:
        raise NonPhysicalPayload(
            f"the load left after removing the end effector has a negative mass ({mass:.4g} kg): "
            f"{described}. Check {setting} (is another end effector configured?), or give the "
            "end effector explicitly",
            setting,
        )
    if abs(mass) <= MASS_TOLERANCE:
        if np.linalg.norm(moment) > MASS_TOLERANCE * MAX_COM_DISTANCE:
            raise NonPhysicalPayload(
                f"the difference has no mass but a first moment of {np.linalg.norm(moment):.3g} "
                f"kg·m (the centres of mass differ): {described}. Check {setting}",
                setting,
            )
        return pin.Inertia.Zero()
    com = moment / mass
    if np.linalg.norm(com) > MAX_COM_DISTANCE:
        raise NonPhysicalPayload(
            f"the load left after removing the end effector ({mass:.4g} kg) would have its centre "
            f"of mass {np.linalg.norm(com):.3g} m from the flange: {described}. Check {setting}",
            setting,
        )
    if measured.inertia is None:  # unknown rotational inertia: the difference as a point mass
        return pin.Inertia(mass, com, np.zeros((3, 3)))
    difference = body.to_pin() - end_effector.to_pin()
    smallest = float(np.linalg.eigvalsh(_symmetric(np.array(difference.inertia)))[0])
    if smallest < -1e-9:
        raise NonPhysicalPayload(
            "the load left after removing the end effector has an inertia that is not positive "
            f"semidefinite (smallest principal moment {smallest:.3g} kg·m²): {described}, and its "
            f"inertia exceeds the measured one. Check {setting}",
            setting,
        )
    return difference


def _symmetric(matrix: np.ndarray) -> np.ndarray:
    return 0.5 * (matrix + matrix.T)
