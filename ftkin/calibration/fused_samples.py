"""Fused samples: raw wrenches with both an orientation (FK or ``R_BS``) and the sensor's IMU.

:class:`FusedSamples` pairs :class:`~ftkin.calibration.samples.Samples` (the orientation of each
reading: joint angles through an arm, or rotations, quaternions, Euler angles given) with the
accelerometer's specific force of the same readings ``[ax, ay, az]`` [m/s², IMU frame; ``+g``
upward at rest], checked as :class:`~ftkin.calibration.imu_samples.ImuSamples` checks it (one
per reading, the median norm about ``g``). Build it with
:meth:`FusedSamples.from_arrays`; :func:`ftkin.calibrate`
then fits both together (:mod:`ftkin.calibration.fused_fit`).
"""

from dataclasses import dataclass, field

import numpy as np

from ..exceptions import InvalidInput
from .imu_samples import ImuPoseAverages, ImuSamples
from .model import STANDARD_GRAVITY
from .samples import PoseAverages, Samples


@dataclass(frozen=True)
class FusedPoseAverages:
    """The readings of each static pose averaged, orientation and IMU alike (same poses, order).

    Attributes:
        orientation: The wrench and ``R_BS`` per pose.
        imu: The accelerometer (and the same wrench) per pose.
    """

    orientation: PoseAverages
    imu: ImuPoseAverages

    def __len__(self) -> int:
        return len(self.orientation)


@dataclass(frozen=True)
class FusedSamples:
    """Raw readings with their orientation and the sensor's IMU.

    Attributes:
        samples: The wrenches with their orientations, pose ids and times.
        specific_force: ``(N, 3)`` accelerometer readings [m/s², IMU frame], ``+g`` upward at
            rest (bias and scale errors included: the calibration estimates them).
        angular_velocity: ``(N, 3)`` gyro readings [rad/s, IMU frame], or None.
        g: Magnitude of gravity [m/s²] (the unit check and the accelerometer's norm).
        accel_count_factor: Independent accelerometer readings per reading, in ``(0, 1]``
            (:attr:`ImuSamples.accel_count_factor <ftkin.calibration.imu_samples.ImuSamples>`:
            below 1 when a slower IMU was interpolated onto the wrench's stamps).
        imu: The same readings as :class:`~ftkin.calibration.imu_samples.ImuSamples` (no
            orientation): the IMU-only fit, or :class:`~ftkin.control.ImuCompensator`.
    """

    samples: Samples
    specific_force: np.ndarray
    angular_velocity: np.ndarray | None = None
    g: float = STANDARD_GRAVITY
    accel_count_factor: float = 1.0
    imu: ImuSamples = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        if not isinstance(self.samples, Samples):
            raise InvalidInput(
                f"samples must be an ftkin.Samples (the orientations), got "
                f"{type(self.samples).__name__}"
            )
        samples = self.samples
        imu = ImuSamples(
            self.specific_force,
            samples.wrenches,
            samples.pose_ids,
            self.angular_velocity,
            samples.times,
            self.g,
            self.accel_count_factor,
        )
        object.__setattr__(self, "imu", imu)
        object.__setattr__(self, "accel_count_factor", imu.accel_count_factor)
        object.__setattr__(self, "specific_force", imu.specific_force)
        object.__setattr__(self, "angular_velocity", imu.angular_velocity)
        object.__setattr__(self, "g", imu.g)

    @classmethod
    def from_arrays(
        cls,
        samples: Samples,
        specific_force,
        *,
        accel_unit: str = "m/s^2",
        angular_velocity=None,
        g: float = STANDARD_GRAVITY,
    ) -> "FusedSamples":
        """``samples`` with the accelerometer in the user's unit (``"m/s^2"`` or ``"g"``)."""
        if not isinstance(samples, Samples):
            raise InvalidInput(f"samples must be an ftkin.Samples, got {type(samples).__name__}")
        imu = ImuSamples.from_arrays(
            specific_force,
            samples.wrenches,
            samples.pose_ids,
            accel_unit=accel_unit,
            angular_velocity=angular_velocity,
            times=samples.times,
            g=g,
        )
        return cls(samples, imu.specific_force, imu.angular_velocity, imu.g)

    def __len__(self) -> int:
        return len(self.samples)

    @property
    def wrenches(self) -> np.ndarray:
        """``(N, 6)`` raw readings [N, N·m], sensor frame."""
        return self.samples.wrenches

    @property
    def rotations(self) -> np.ndarray:
        """``(N, 3, 3)`` ``R_BS`` of the orientation's sensor frame (the URDF's for joints)."""
        return self.samples.rotations

    @property
    def pose_ids(self) -> np.ndarray:
        return self.samples.pose_ids

    @property
    def joint_positions(self) -> np.ndarray | None:
        return self.samples.joint_positions

    @property
    def times(self) -> np.ndarray | None:
        return self.samples.times

    def pose_averages(self) -> FusedPoseAverages:
        """Average the readings of each pose (orientations and accelerometer; a pose whose
        orientation or specific force turns by more than 2° is refused)."""
        return FusedPoseAverages(self.samples.pose_averages(), self.imu.pose_averages())
