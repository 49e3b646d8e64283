"""Compensation from the sensor's IMU: no arm model, the accelerometer gives gravity and the
linear acceleration together, the gyro the rotation.

Per reading (:mod:`ftkin.calibration.imu_model`)::

    contact = raw − [F0, M0] + Y([0, ω], [f_S, α]) θ
    f_S = R_SI (a − b) ⊘ (1 + s) − α × r − ω × (ω × r),   ω = R_SI w,  α = R_SI ẇ

At rest, or without a gyro: ``F' = F − F0 + m f_S``, ``M' = M − M0 + m c × f_S``. ``raw`` is the
reading times the calibration's :attr:`~ftkin.calibration.CalibrationResult.reading_signs` (a
fused calibration of a sensor that reports the reaction, ``sensor_sign=-1``, or a reversed axis),
as in :class:`~ftkin.control.Compensator`. θ is the
calibration's inertia (a dynamic calibration) or its point mass ``[m, m c, 0…]``; ``r`` is the
calibration's ``imu_position`` (given or estimated) or zero.

Three paths, one formula: :meth:`ImuCompensator.compensate_batch` is the formula
(:func:`~ftkin.calibration.imu_model.predict_imu`, vectorized); :meth:`~ImuCompensator.compensate`
and :meth:`~ImuCompensator.compensate_moving` are the control tick's fast paths
(:class:`~ftkin.calibration.imu_model.ImuFloatModel`, tested against the formula);
:meth:`~ImuCompensator.compensate_stream` estimates ``ẇ`` online with the dynamic path's causal
Savitzky–Golay filter (a known delay) and :meth:`~ImuCompensator.compensate_recording` offline with
its zero-phase one.
"""

import math
from collections import deque

import numpy as np

from ..calibration.derivatives import DEFAULT_POLYORDER, CausalDifferentiator, joint_derivatives
from ..calibration.fused_samples import FusedSamples
from ..calibration.imu_model import ImuFloatModel, predict_imu, specific_force_in_sensor
from ..calibration.imu_result import ImuCalibrationResult
from ..calibration.imu_samples import ImuSamples
from ..exceptions import InvalidInput
from ..validation import (
    FLOAT64,
    MAX_IMU_VALUE,
    MAX_WRENCH,
    as_batch,
    as_vector,
    as_wrench,
    as_wrenches,
)


def _floats(values, size: int, name: str, bound: float) -> list:
    """``values`` as ``size`` finite Python floats within ``±bound``, or :class:`InvalidInput`."""
    try:
        if type(values) is np.ndarray and values.dtype is FLOAT64:
            out = values.tolist()
        else:
            out = np.asarray(values, dtype=np.float64).tolist()
    except (TypeError, ValueError) as error:
        raise InvalidInput(f"{name} must be numeric: {error}") from None
    if type(out) is not list or len(out) != size or type(out[0]) is not float:
        raise InvalidInput(f"{name} must have shape ({size},), got {np.shape(values)}")
    if not math.hypot(*out) <= bound:  # NaN, inf or a huge entry
        array = np.asarray(out)
        if not np.all(np.isfinite(array)):
            raise InvalidInput(f"{name} must be finite, got {out}")
        raise InvalidInput(f"{name} is beyond ±{bound:g}: {out} (a unit mistake?)")
    return out


class ImuCompensator:
    """Remove the sensor bias, the tool's weight and its inertial wrench using the sensor's IMU.

    Args:
        calibration: An :class:`~ftkin.calibration.imu_result.ImuCalibrationResult`
            (``ftkin.calibrate`` of ``ImuSamples.from_arrays``, or the dynamic fit).
        imu_position: ``r`` ``(3,)`` [m, sensor frame] overriding the calibration's (a datasheet
            value); the lever arm needs the gyro.
        inertial_parameters: θ ``(10,)`` overriding the calibration's (sensor frame).
    """

    def __init__(self, calibration, *, imu_position=None, inertial_parameters=None):
        if not isinstance(calibration, ImuCalibrationResult):
            raise InvalidInput(
                "calibration must be a calibration from the IMU (ImuCalibrationResult), got "
                f"{type(calibration).__name__}; an FK calibration compensates with Compensator"
            )
        self.calibration = calibration
        position = imu_position if imu_position is not None else calibration.imu_position
        self.imu_position = (
            np.zeros(3) if position is None else as_vector(position, 3, "imu_position [m]")
        )
        self.inertial_parameters = (
            calibration.dynamic_parameters
            if inertial_parameters is None
            else as_vector(inertial_parameters, 10, "inertial_parameters")
        )
        self._bias = np.array(calibration.bias)
        signs = calibration.reading_signs  # the tick's copy is _sign_floats (no conversion)
        self._reading_signs = None if np.all(signs == 1.0) else signs
        self._sign_floats = tuple(signs.tolist())
        self._model = ImuFloatModel(
            calibration.imu_rotation,
            calibration.accel_bias,
            calibration.accel_scale,
            self._bias,
            self.inertial_parameters,
            self.imu_position,
        )
        # the unchecked kernels (six floats out), the stored signs applied to the reading
        signed = self._reading_signs is not None
        self.contact_floats = self._signed_contact if signed else self._model.contact
        self.contact_moving_floats = (
            self._signed_contact_moving if signed else self._model.contact_moving
        )
        self._stream: CausalDifferentiator | None = None
        self._raw_buffer: deque = deque()

    def _signed(self, raw) -> tuple[float, ...]:
        """The six floats of a reading times the stored signs (a reading of another length
        raises instead of being cut)."""
        (s0, s1, s2, s3, s4, s5), (w0, w1, w2, w3, w4, w5) = self._sign_floats, raw
        return (w0 * s0, w1 * s1, w2 * s2, w3 * s3, w4 * s4, w5 * s5)

    def _signed_contact(self, raw, accel):
        return self._model.contact(self._signed(raw), accel)

    def _signed_contact_moving(self, raw, accel, gyro, rate):
        return self._model.contact_moving(self._signed(raw), accel, gyro, rate)

    def __repr__(self) -> str:
        calibration = self.calibration
        return (
            f"ImuCompensator(tool {calibration.tool_mass:.4g} kg, COM "
            f"{np.round(calibration.center_of_mass, 4).tolist()} m, IMU at "
            f"{np.round(self.imu_position, 4).tolist()} m, inertia "
            f"{'identified' if calibration.has_inertia else 'point mass'})"
        )

    @property
    def bias(self) -> np.ndarray:
        """The bias ``[F0, M0]`` [N, N·m] subtracted now (a copy)."""
        return self._bias.copy()

    def set_bias(self, bias) -> None:
        """Use ``bias`` ``(6,)`` [N, N·m] from now on (a re-zero)."""
        self._bias = as_wrench(bias, "bias [F0, M0]")
        calibration = self.calibration
        self._model.set(
            calibration.imu_rotation,
            calibration.accel_bias,
            calibration.accel_scale,
            self._bias,
            self.inertial_parameters,
            self.imu_position,
        )

    # ------------------------------------------------------------ one sample
    def compensate(self, raw_wrench, specific_force) -> np.ndarray:
        """Contact wrench ``(6,)`` [N, N·m] from one raw reading and the accelerometer's
        ``[ax, ay, az]`` [m/s², IMU frame]: gravity and the linear acceleration (the tool's
        rotation ignored: see :meth:`compensate_moving`).
        """
        raw = _floats(raw_wrench, 6, "raw_wrench", MAX_WRENCH)
        accel = _floats(specific_force, 3, "specific_force [m/s²]", MAX_IMU_VALUE)
        return np.array(self.contact_floats(raw, accel))

    def compensate_moving(
        self, raw_wrench, specific_force, angular_velocity, angular_acceleration
    ) -> np.ndarray:
        """Contact wrench ``(6,)`` with the gyro's ``w`` [rad/s] and its rate ``ẇ`` [rad/s²] (IMU
        frame): the lever arm and the rotational inertia included.
        """
        if (
            type(raw_wrench)
            is type(specific_force)
            is type(angular_velocity)
            is type(angular_acceleration)
            is np.ndarray
            and raw_wrench.dtype
            is specific_force.dtype
            is angular_velocity.dtype
            is angular_acceleration.dtype
            is FLOAT64
            and raw_wrench.ndim == specific_force.ndim == 1
        ):  # the common case, float64 vectors: one length test and two norms (NaN fails both)
            raw, accel = raw_wrench.tolist(), specific_force.tolist()
            gyro, rate = angular_velocity.tolist(), angular_acceleration.tolist()
            try:  # a gyro of shape (3, 1) fails the norm: the checks below name it
                if (
                    len(raw) == 6
                    and len(accel) == len(gyro) == len(rate) == 3
                    and math.hypot(*raw) <= MAX_WRENCH
                    and math.hypot(*accel, *gyro, *rate) <= MAX_IMU_VALUE
                ):
                    return np.array(self.contact_moving_floats(raw, accel, gyro, rate))
            except TypeError:
                pass
        raw = _floats(raw_wrench, 6, "raw_wrench", MAX_WRENCH)
        accel = _floats(specific_force, 3, "specific_force [m/s²]", MAX_IMU_VALUE)
        gyro = _floats(angular_velocity, 3, "angular_velocity [rad/s]", MAX_IMU_VALUE)
        rate = _floats(angular_acceleration, 3, "angular_acceleration [rad/s²]", MAX_IMU_VALUE)
        return np.array(self.contact_moving_floats(raw, accel, gyro, rate))

    # ---------------------------------------------------------------- stream
    def start_stream(
        self, sample_period: float, window: int | None = None, polyorder: int = DEFAULT_POLYORDER
    ) -> float:
        """Estimate ``ẇ`` (and smooth ``w`` and ``a``) online with the causal Savitzky–Golay
        filter of the dynamic path; returns its delay [s].
        """
        self._stream = CausalDifferentiator(6, sample_period, window, polyorder)
        self._raw_buffer = deque(maxlen=self._stream.window)
        return self._stream.delay

    def compensate_stream(self, raw_wrench, specific_force, angular_velocity) -> np.ndarray | None:
        """Push one reading with its IMU sample; the contact wrench of the sample ``delay``
        seconds ago (raw delayed with the estimates), or None while the window fills.
        """
        if self._stream is None:
            raise InvalidInput("call start_stream(sample_period) before compensate_stream")
        raw = _floats(raw_wrench, 6, "raw_wrench", MAX_WRENCH)
        accel = _floats(specific_force, 3, "specific_force [m/s²]", MAX_IMU_VALUE)
        gyro = _floats(angular_velocity, 3, "angular_velocity [rad/s]", MAX_IMU_VALUE)
        estimate = self._stream.update(np.array(gyro + accel))
        self._raw_buffer.append(raw)
        if estimate is None:
            return None
        smooth, rate = estimate[0].tolist(), estimate[1].tolist()
        return np.array(
            self.contact_moving_floats(
                self._raw_buffer[(self._stream.window - 1) // 2], smooth[3:], smooth[:3], rate[:3]
            )
        )

    # ----------------------------------------------------------------- batch
    def compensate_batch(
        self, raw_wrenches, specific_force, angular_velocity=None, angular_acceleration=None
    ) -> np.ndarray:
        """Contact wrenches ``(N, 6)`` by the formula (vectorized), signals as given (IMU frame).

        Without ``angular_velocity`` the tool is taken at rest (its rotation ignored); with it,
        ``angular_acceleration`` is needed too (see :meth:`compensate_recording` to estimate it).
        """
        raw, _ = as_wrenches(raw_wrenches, "raw_wrenches")
        if self._reading_signs is not None:
            raw = raw * self._reading_signs
        accel, _ = as_batch(specific_force, 3, "specific_force [m/s²]")
        if len(accel) != len(raw):
            raise InvalidInput(
                f"{len(raw)} wrenches but {len(accel)} accelerometer samples; expected one each"
            )
        omega = alpha = None
        if angular_velocity is not None or angular_acceleration is not None:
            if angular_velocity is None or angular_acceleration is None:
                raise InvalidInput("give both angular_velocity and angular_acceleration, or none")
            gyro, _ = as_batch(angular_velocity, 3, "angular_velocity [rad/s]")
            rate, _ = as_batch(angular_acceleration, 3, "angular_acceleration [rad/s²]")
            if not len(gyro) == len(rate) == len(raw):
                raise InvalidInput(
                    f"{len(raw)} wrenches, {len(gyro)} gyro samples and {len(rate)} rates; "
                    "expected one each"
                )
            rotation = self.calibration.imu_rotation
            omega, alpha = gyro @ rotation.T, rate @ rotation.T
        calibration = self.calibration
        force = specific_force_in_sensor(
            accel,
            calibration.imu_rotation,
            calibration.accel_bias,
            calibration.accel_scale,
            self.imu_position if omega is not None else None,
            omega,
            alpha,
        )
        return raw - predict_imu(self._bias, self.inertial_parameters, force, omega, alpha)

    def compensate_recording(
        self, samples: ImuSamples, window: int | None = None, polyorder: int = DEFAULT_POLYORDER
    ) -> np.ndarray:
        """Contact wrenches ``(N, 6)`` of a recording (in the samples' order).

        With times and a gyro: ``w`` and ``a`` smoothed and ``ẇ`` estimated by the zero-phase
        Savitzky–Golay filter (:func:`~ftkin.calibration.derivatives.joint_derivatives`), then
        :meth:`compensate_batch`; otherwise the tool is taken at rest. Fused samples (an
        orientation too) are compensated from their IMU readings alone.
        """
        if isinstance(samples, FusedSamples):
            samples = samples.imu
        if not isinstance(samples, ImuSamples):
            raise InvalidInput(f"samples must be ftkin ImuSamples, got {type(samples).__name__}")
        if samples.angular_velocity is None or samples.times is None:
            return self.compensate_batch(samples.wrenches, samples.specific_force)
        order = np.argsort(samples.times, kind="stable")
        signals = np.concatenate([samples.angular_velocity, samples.specific_force], axis=1)
        smooth, rate, _ = joint_derivatives(samples.times[order], signals[order], window, polyorder)
        out = np.empty((len(samples), 6))
        out[order] = self.compensate_batch(
            samples.wrenches[order], smooth[:, 3:], smooth[:, :3], rate[:, :3]
        )
        return out
