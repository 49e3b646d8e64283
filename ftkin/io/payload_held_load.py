"""A load held below the tool (identified online) as part of the controller's payload.

:class:`~ftkin.control.load_events.LoadTracker` identifies what the gripper took: its mass and
centre of mass in the **sensor** frame. The controller is told the tool and the held load as one
rigid body in its flange frame (:func:`~ftkin.io.payload_export.held_load_in_flange`,
:func:`combined_payload`). A held load's file (``ftkin export --held-load LOAD.json``) is JSON::

    {"mass": 0.3245, "center_of_mass": [0.012, -0.006, 0.07]}

``mass`` [kg] and ``center_of_mass`` [m, sensor frame] of the held load alone (the tool is the
calibration's); an optional ``inertia`` ``[ixx, iyy, izz, ixy, ixz, iyz]`` [kg·m²] about its
centre of mass, sensor axes (default: a point mass).
"""

import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..exceptions import InvalidInput
from ..validation import as_float_array
from .payload_inertia import Payload, RigidBody, checked_inertia

HELD_LOAD_KEYS = ("mass", "center_of_mass", "inertia")
"""The keys a held load's JSON may have (``inertia`` optional)."""


@dataclass(frozen=True)
class HeldLoad:
    """A load held below the tool, in the sensor frame.

    Attributes:
        mass: [kg] (≥ 0; 0: nothing held).
        center_of_mass: ``(3,)`` its centre of mass in the sensor frame [m], finite.
        inertia: ``(3, 3)`` about its centre of mass, sensor axes [kg·m²], or None (a point mass).

    Raises:
        InvalidInput: a mass that is not a finite number ≥ 0, a centre of mass that is not three
            finite numbers (an undetermined component: turn the wrist while holding the load), or
            an inertia that no body has.
    """

    mass: float
    center_of_mass: np.ndarray
    inertia: np.ndarray | None = None

    def __post_init__(self):
        mass = self.mass
        if isinstance(mass, bool) or not isinstance(mass, (int, float, np.floating)):
            raise InvalidInput(f"the held load's mass must be a number [kg], got {mass!r}")
        if not (math.isfinite(mass) and mass >= 0.0):
            raise InvalidInput(f"the held load's mass must be finite and >= 0 kg, got {mass!r}")
        com = as_float_array(self.center_of_mass, "the held load's centre of mass [m]")
        if com.shape != (3,):
            raise InvalidInput(
                f"the held load's centre of mass must be 3 numbers [m], got shape {com.shape}"
            )
        if not np.all(np.isfinite(com)):
            raise InvalidInput(
                f"the held load's centre of mass {com.tolist()} m is not determined along every "
                "sensor axis: turn the wrist about an axis across gravity while holding it (or "
                "give its centre of mass)"
            )
        com = com.copy()
        com.setflags(write=False)
        inertia = checked_inertia(self.inertia)
        if inertia is not None:
            inertia.setflags(write=False)
        object.__setattr__(self, "mass", float(mass))
        object.__setattr__(self, "center_of_mass", com)
        object.__setattr__(self, "inertia", inertia)

    def to_dict(self) -> dict:
        """The JSON document (see the module docstring)."""
        document = {"mass": self.mass, "center_of_mass": self.center_of_mass.tolist()}
        if self.inertia is not None:
            i = self.inertia
            document["inertia"] = [i[0, 0], i[1, 1], i[2, 2], i[0, 1], i[0, 2], i[1, 2]]
        return document


def read_held_load(path) -> HeldLoad:
    """A :class:`HeldLoad` from its JSON file (see the module docstring).

    Raises:
        InvalidInput: the file is missing, not JSON, not an object of :data:`HELD_LOAD_KEYS`, or
            its values are not a load (the message names what was expected).
    """
    path = Path(path)
    try:
        document = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise InvalidInput(f"no held-load file {str(path)!r}") from None
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as error:
        raise InvalidInput(
            f"{str(path)!r} is not a held load's JSON ({error}); expected "
            '{"mass": KG, "center_of_mass": [X, Y, Z]} (sensor frame, m)'
        ) from None
    if not isinstance(document, dict) or not {"mass", "center_of_mass"} <= set(document):
        raise InvalidInput(
            f"{str(path)!r} must hold a JSON object with 'mass' [kg] and 'center_of_mass' "
            "[x, y, z] [m, sensor frame]"
        )
    unknown = sorted(set(document) - set(HELD_LOAD_KEYS))
    if unknown:
        raise InvalidInput(
            f"{str(path)!r} has keys ftkin does not know: {', '.join(unknown)} (it takes "
            f"{', '.join(HELD_LOAD_KEYS)})"
        )
    return HeldLoad(document["mass"], document["center_of_mass"], document.get("inertia"))


def combined_payload(payload: Payload, body: RigidBody) -> Payload:
    """``payload`` and ``body`` as one rigid body (both in the payload's flange frame).

    The mass adds, the centre of mass is the mass-weighted mean, and the inertia is about the
    combined centre of mass (each body's own inertia moved by the parallel-axis theorem; a
    payload without a known inertia counts as a point mass, so the result's inertia is that of
    the two centres of mass at least).
    """
    if not isinstance(payload, Payload) or not isinstance(body, RigidBody):
        raise InvalidInput("combined_payload takes an ftkin Payload and a RigidBody")
    own = np.zeros((3, 3)) if payload.inertia is None else payload.inertia
    total = RigidBody(payload.mass, payload.center_of_mass, own).to_pin() + body.to_pin()
    mass = float(total.mass)
    if not mass > 0.0:
        return payload
    inertia = np.array(total.inertia)
    return Payload(mass, np.array(total.lever), payload.flange_frame, 0.5 * (inertia + inertia.T))
