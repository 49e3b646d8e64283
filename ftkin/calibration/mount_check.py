"""The check of the sensor's mount by the fused fit: :class:`MountCheck` and the warning that names
a disagreement.

The fused fit (:mod:`ftkin.calibration.fused_fit`) estimates the rotation ``R_M`` from the
orientation's sensor frame (the URDF's) to the real sensor frame with the mount free, whatever
it reports, and tests it against the identity::

    φ = Log(R_M),   Σ_φ = J Σ_δ Jᵀ  (J = ∂Log(R_M Exp(δ))/∂δ),   χ² = φᵀ Σ_φ⁻¹ φ   (3 dof)

A mount beyond the noise (``p`` below :data:`MOUNT_CHECK_P`) and larger than the tolerance is
the mount error a URDF hides: a warning names its angle, its axis and the fix. Per pose, the
angle between the gravity the URDF predicts in its sensor frame and the one measured (the
accelerometer through ``R_SI``) says where it shows.
"""

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..exceptions import InvalidInput
from .mount import rotation_to_rpy

MOUNT_CHECK_P = 1e-3
"""Largest p-value of the mount's chi-square (3 dof) that counts as beyond the noise."""

SOURCES = ("accelerometer", "wrench")
"""What tells the mount from the IMU's rotation: the accelerometer (``R_SI`` given, with the
wrench) or the wrench alone (``R_SI`` estimated)."""


def _chi2_sf(value: float, dof: int) -> float:
    from scipy.stats import chi2  # scipy.stats loads where it is used

    return float(chi2.sf(value, dof))


@dataclass(frozen=True)
class MountCheck:
    """The mount ``R_M`` the IMU and the wrench see, against the orientation's sensor frame.

    Attributes:
        rotation: ``R_M`` ``(3, 3)``: orientation's (URDF's) sensor frame → real sensor frame.
        covariance: ``(3, 3)`` covariance of ``φ = Log(R_M)`` [rad²].
        pose_angles_deg: ``(P,)`` angle [deg] per pose between the gravity direction the
            orientation predicts (in its sensor frame) and the one measured.
        source: ``"accelerometer"`` or ``"wrench"`` (:data:`SOURCES`).
        tolerance_deg: Smallest angle [deg] warned about.
        frame: The sensor frame's name (the URDF's), or None for rotations given directly.
    """

    rotation: np.ndarray
    covariance: np.ndarray
    pose_angles_deg: np.ndarray
    source: str
    tolerance_deg: float
    frame: str | None = None

    def __post_init__(self):
        rotation = np.array(self.rotation, dtype=float)
        if (
            rotation.shape != (3, 3)
            or not np.allclose(rotation @ rotation.T, np.eye(3), atol=1e-6)
            or np.linalg.det(rotation) <= 0.0
        ):
            raise InvalidInput(f"the mount check's rotation must be a rotation, got {rotation}")
        covariance = np.array(self.covariance, dtype=float)
        if covariance.shape != (3, 3) or not np.all(np.isfinite(covariance)):
            raise InvalidInput("the mount check's covariance must be a finite (3, 3) array")
        angles = np.array(self.pose_angles_deg, dtype=float).reshape(-1)
        if self.source not in SOURCES:
            raise InvalidInput(f"source must be one of {', '.join(SOURCES)}, got {self.source!r}")
        if not (np.isfinite(self.tolerance_deg) and self.tolerance_deg >= 0.0):
            raise InvalidInput(f"tolerance_deg must be ≥ 0, got {self.tolerance_deg!r}")
        for name, value in (("rotation", rotation), ("covariance", covariance)):
            value.setflags(write=False)
            object.__setattr__(self, name, value)
        angles.setflags(write=False)
        object.__setattr__(self, "pose_angles_deg", angles)
        object.__setattr__(self, "tolerance_deg", float(self.tolerance_deg))

    @classmethod
    def from_increment_covariance(
        cls, rotation, increment_covariance, pose_angles_deg, source, tolerance_deg, frame=None
    ) -> "MountCheck":
        """From ``R_M`` and the covariance of its increments ``δ`` (``R_M Exp(δ)``) [rad²]."""
        rotation = np.asarray(rotation, dtype=float)
        jacobian = pin.Jlog3(rotation)  # ∂Log(R Exp(δ))/∂δ at δ = 0
        covariance = jacobian @ np.asarray(increment_covariance, dtype=float) @ jacobian.T
        covariance = 0.5 * (covariance + covariance.T)
        return cls(rotation, covariance, pose_angles_deg, source, tolerance_deg, frame)

    @property
    def rotation_vector(self) -> np.ndarray:
        """``φ = Log(R_M)`` ``(3,)`` [rad], axes of the orientation's sensor frame."""
        return np.asarray(pin.log3(self.rotation), dtype=float)

    @property
    def angle_deg(self) -> float:
        """``|φ|`` [deg]: how far the real sensor frame is turned from the URDF's."""
        return float(np.rad2deg(np.linalg.norm(self.rotation_vector)))

    @property
    def std_deg(self) -> np.ndarray:
        """``(3,)`` standard errors [deg] of ``φ`` about x, y, z."""
        return np.rad2deg(np.sqrt(np.clip(np.diag(self.covariance), 0.0, None)))

    @property
    def angle_std_deg(self) -> float:
        """Standard error [deg] of :attr:`angle_deg` (along ``φ``; the largest one near zero)."""
        phi = self.rotation_vector
        norm = float(np.linalg.norm(phi))
        if norm < 1e-12:
            return float(np.max(self.std_deg))
        axis = phi / norm
        return float(np.rad2deg(np.sqrt(max(axis @ self.covariance @ axis, 0.0))))

    @property
    def rpy_deg(self) -> np.ndarray:
        """``(3,)`` roll, pitch, yaw [deg] of ``R_M`` (``R = Rz(yaw) Ry(pitch) Rx(roll)``)."""
        return np.rad2deg(rotation_to_rpy(self.rotation))

    @property
    def chi_square(self) -> float:
        """``φᵀ Σ_φ⁻¹ φ``: the mount against the identity, in units of its noise (3 dof)."""
        phi = self.rotation_vector
        return float(phi @ np.linalg.pinv(self.covariance, hermitian=True) @ phi)

    @property
    def p_value(self) -> float:
        """Probability of a chi-square this large with a sensor mounted as the URDF says."""
        return _chi2_sf(self.chi_square, 3)

    @property
    def axis(self) -> str:
        """The sensor axis the mount turns about most (``"x"``, ``"y"`` or ``"z"``)."""
        return "xyz"[int(np.argmax(np.abs(self.rotation_vector)))]

    @property
    def significant(self) -> bool:
        """True when the mount is beyond the noise and larger than the tolerance."""
        return self.p_value < MOUNT_CHECK_P and self.angle_deg > self.tolerance_deg

    def message(self, estimated: bool) -> str:
        """The warning: which angle, how many degrees, what it means and the fix.

        ``estimated``: the calibration estimated the mount (and applies it).
        """
        urdf = self.frame is not None
        frame = f"the URDF's sensor frame {self.frame!r}" if urdf else "the rotations' frame"
        what = "mounted as the URDF says" if urdf else "oriented as the given rotations say"
        who = (
            f"the sensor (or the IMU) is not {what}"
            if self.source == "accelerometer"
            else f"the sensor is not {what}"
        )
        seen = (
            "the accelerometer (R_SI given) and the wrench see"
            if self.source == "accelerometer"
            else "the wrench (with R_SI estimated, only the wrench tells the mount from the "
            "IMU's rotation) sees"
        )
        rpy = ", ".join(f"{v:+.2f}" for v in self.rpy_deg)
        correction = ", ".join(f"{v:+.3f}" for v in np.rad2deg(rotation_to_rpy(self.rotation.T)))
        source_fix = (
            f"correct the URDF: turn the sensor frame by rpy [{correction}]° (R_Mᵀ)"
            if urdf
            else "correct the rotations' source: the sensor is turned by R_M from the frame "
            "they give (a mount is estimated only from joint angles)"
        )
        if estimated:
            fix = (
                "the calibration estimated it and applies it (mount_rotation); to remove it at "
                f"the source, {source_fix}"
            )
        else:
            estimate = "calibrate with estimate_mount='full' (--estimate-mount full), or "
            fix = (
                (estimate if urdf else "")
                + f"{source_fix}; until then the offsets and the centre of mass absorb it "
                "(beyond a few degrees the mass and tilt too)"
            )
        return (
            f"{who}: {seen} the real sensor frame turned {self.angle_deg:.3f}° ± "
            f"{self.angle_std_deg:.3f}° from {frame}, mostly about its {self.axis} axis (R_M rpy "
            f"[{rpy}]°; chi-square {self.chi_square:.3g} for 3 dof, p = {self.p_value:.2g}: beyond "
            f"the noise; up to {float(np.max(self.pose_angles_deg, initial=0.0)):.2f}° at a pose); "
            f"{fix}"
        )

    def to_dict(self) -> dict:
        """The JSON form (read back by :meth:`from_dict`)."""
        return {
            "rotation": self.rotation.tolist(),
            "rpy_deg": self.rpy_deg.tolist(),
            "angle_deg": self.angle_deg,
            "covariance": self.covariance.tolist(),
            "std_deg": self.std_deg.tolist(),
            "chi_square": self.chi_square,
            "p_value": self.p_value,
            "significant": self.significant,
            "pose_angles_deg": self.pose_angles_deg.tolist(),
            "source": self.source,
            "tolerance_deg": self.tolerance_deg,
            "frame": self.frame,
        }

    @classmethod
    def from_dict(cls, data: dict) -> "MountCheck":
        """From :meth:`to_dict`'s form (the derived figures are recomputed, not read)."""
        return cls(
            np.asarray(data["rotation"], dtype=float),
            np.asarray(data["covariance"], dtype=float),
            np.asarray(data["pose_angles_deg"], dtype=float),
            str(data["source"]),
            float(data["tolerance_deg"]),
            data.get("frame"),
        )
