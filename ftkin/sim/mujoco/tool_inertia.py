"""A rigid load carried by the sensor: its mass, centre of mass and inertia (sensor frame).

Shared by the MuJoCo scene (:class:`~ftkin.sim.mujoco.arm_model.ArmSimulation`)
and the inverse-dynamics recorder (:class:`~ftkin.sim.mujoco.recording.MujocoRecorder`).
"""

from dataclasses import dataclass

import numpy as np

from ...calibration.log_cholesky import parameters_from_body
from ...exceptions import InvalidInput
from ...validation import as_positive, as_vector


@dataclass(frozen=True)
class ToolInertia:
    """A rigid load on the sensor: mass, centre of mass and inertia, in the sensor frame.

    Attributes:
        mass: [kg].
        center_of_mass: ``(3,)`` in the sensor frame [m].
        inertia_about_com: ``(3, 3)`` about the COM, sensor axes [kg·m²].
    """

    mass: float
    center_of_mass: np.ndarray
    inertia_about_com: np.ndarray

    def __post_init__(self):
        object.__setattr__(self, "mass", as_positive(self.mass, "mass"))
        object.__setattr__(
            self, "center_of_mass", as_vector(self.center_of_mass, 3, "center_of_mass")
        )
        inertia = np.asarray(self.inertia_about_com, dtype=float)
        if (
            inertia.shape != (3, 3)
            or not np.allclose(inertia, inertia.T)
            or np.linalg.eigvalsh(inertia)[0] <= 0
        ):
            raise InvalidInput(
                "inertia_about_com must be a symmetric positive definite (3, 3) matrix, got "
                f"{inertia!r}"
            )
        object.__setattr__(self, "inertia_about_com", inertia)

    def parameters(self) -> np.ndarray:
        """The ten inertial parameters θ about the sensor origin, ``[m, m·c, Ixx, Ixy, Iyy, Ixz,
        Iyz, Izz]`` (Pinocchio's order).
        """
        return parameters_from_body(self.mass, self.center_of_mass, self.inertia_about_com)
