"""The result of the fused calibration (an orientation and the IMU): a
:class:`FusedCalibrationResult`.

Both an FK calibration and an IMU calibration: the FK fields hold what they hold there
(``gravity_in_base`` with the real base tilt, the 12×12 covariance over ``θ = [a, F0, M0, P]``,
the URDF, the mount ``R_M``), the IMU fields ``R_SI`` (IMU → **real** sensor frame), the
accelerometer's bias and scale with their covariance; and :attr:`mount_check`, the mount the IMU
and the wrench see against the URDF's sensor frame. So it compensates with the FK path
(:class:`~ftkin.control.Compensator` with the arm) and with the IMU's
(:class:`~ftkin.control.ImuCompensator`), and saves with the keys of both.
"""

from dataclasses import dataclass

import numpy as np

from ..exceptions import InvalidInput
from .imu_result import ImuCalibrationResult
from .mount_check import MountCheck
from .result import CalibrationResult


@dataclass(frozen=True)
class FusedCalibrationResult(ImuCalibrationResult):
    """A calibration from an orientation (FK or ``R_BS``) and the sensor's accelerometer.

    Inherits :class:`~ftkin.calibration.imu_result.ImuCalibrationResult` (and so
    :class:`~ftkin.calibration.CalibrationResult`): ``force_offset`` [N], ``torque_offset``
    [N·m], ``center_of_mass`` [m, real sensor frame], ``gravity_in_base`` [N, base frame; with
    the tilt the accelerometer and the wrench see], ``mount_rotation`` ``R_M`` (identity unless
    estimated), ``imu_rotation`` ``R_SI`` (IMU → real sensor frame), ``accel_bias``,
    ``accel_scale`` and the covariance of every estimated parameter (``parameter_names``:
    ``gravity_in_base[x]``, ..., ``mount[z]``, ``imu_rotation[x]``, ``accel_bias[x]``, ...).

    Attributes:
        mount_check: The mount the IMU and the wrench see against the orientation's sensor frame
            (:class:`~ftkin.calibration.mount_check.MountCheck`), or None when the poses cannot
            determine it (said in the warnings).
    """

    mount_check: MountCheck | None = None

    def __post_init__(self):
        super().__post_init__()
        if self.mount_check is not None and not isinstance(self.mount_check, MountCheck):
            raise InvalidInput(
                f"mount_check must be a MountCheck or None, got {type(self.mount_check).__name__}"
            )

    def summary(self) -> str:
        """Readable summary with units (± standard error): the FK calibration's lines, the
        IMU's and the mount check."""
        lines = CalibrationResult.summary(self).splitlines()
        lines[0] = lines[0].replace("ftkin calibration:", "ftkin calibration from FK and the IMU:")
        lines += self.imu_summary_lines()
        check = self.mount_check
        if check is not None:
            rpy = ", ".join(f"{v:+.3f}" for v in check.rpy_deg)
            std = ", ".join(f"{v:.3f}" for v in check.std_deg)
            verdict = "BEYOND the noise" if check.significant else "within the noise"
            lines.insert(
                len(lines) - len(self.imu_warnings),
                f"  mount check     R_M rpy = [{rpy}]° ± [{std}]° ({check.angle_deg:.3f}°, seen "
                f"by the {check.source}; chi-square {check.chi_square:.3g} for 3 dof, p = "
                f"{check.p_value:.2g}: {verdict})",
            )
        return "\n".join(lines)

    @property
    def pose_gravity_angles_deg(self) -> np.ndarray:
        """``(P,)`` per pose: the angle [deg] between the gravity direction the orientation
        predicts and the one measured (empty without a mount check)."""
        return np.zeros(0) if self.mount_check is None else self.mount_check.pose_angles_deg
