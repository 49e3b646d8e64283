"""IMU samples: raw wrenches paired with the sensor's own accelerometer (and gyro), no orientation.

:class:`ImuSamples` holds ``N`` raw readings ``[fx, fy, fz, mx, my, mz]`` [N, N·m] (sensor frame),
the accelerometer's specific force ``[ax, ay, az]`` [m/s², IMU frame; ``+g`` upward at rest], and
optionally the gyro's ``[wx, wy, wz]`` [rad/s, IMU frame], pose ids (readings of one static pose)
and times [s]. Build it with :meth:`ImuSamples.from_arrays` (which converts ``accel_unit="g"``);
:func:`ftkin.calibrate` then fits the IMU model (:mod:`ftkin.calibration.imu_fit`).

The unit is checked here, once: the median norm of the specific force must be about ``g``. A
norm of about 1 is a log in g (``accel_unit="g"``), about ``g²`` is m/s² converted twice, about 0
is a linear acceleration with gravity removed (not a specific force); anything else is refused.
"""

from dataclasses import dataclass

import numpy as np

from ..exceptions import InvalidInput, InvalidSamples
from ..validation import (
    as_batch,
    as_float_array,
    as_integers,
    as_positive,
    as_real,
    check_wrench_magnitude,
)
from .model import STANDARD_GRAVITY, check_gravity
from .samples import MAX_POSE_SPREAD, check_time_span

ACCEL_UNITS = {"m/s^2": "m/s^2", "m/s2": "m/s^2", "m/s²": "m/s^2", "mps2": "m/s^2", "g": "g"}
"""Accepted spellings of the accelerometer's unit (``--accel-unit``), and what each means."""

UNIT_TOLERANCE = 0.25
"""Largest relative difference of the median specific-force norm from ``g`` (a moving recording
and a biased, scaled accelerometer stay well inside)."""

MAX_ANGULAR_RATE = 35.0
"""Largest plausible gyro reading [rad/s] (2000 °/s, the widest common range): beyond, °/s."""


def accel_unit_factor(unit: str, g: float = STANDARD_GRAVITY) -> float:
    """Factor from ``unit`` (:data:`ACCEL_UNITS`) to m/s² (``g`` for g)."""
    if not isinstance(unit, str) or unit.strip().lower() not in ACCEL_UNITS:
        raise InvalidInput(
            f"unknown accelerometer unit {unit!r}; expected 'm/s^2' (the default) or 'g'"
        )
    return g if ACCEL_UNITS[unit.strip().lower()] == "g" else 1.0


def check_specific_force_unit(
    specific_force: np.ndarray, g: float = STANDARD_GRAVITY, unit: str = "m/s^2", source=None
) -> None:
    """Refuse a specific force ``(N, 3)`` [m/s²] whose median norm is not about ``g``.

    ``unit`` is the unit the values were given in (named in the fix).
    """
    median = float(np.median(np.linalg.norm(specific_force, axis=1)))
    if abs(median / g - 1.0) <= UNIT_TOLERANCE:
        return
    given = ACCEL_UNITS.get(str(unit).strip().lower(), str(unit))
    if abs(median - 1.0) <= UNIT_TOLERANCE and given != "g":
        hint = (
            "that is about 1: the accelerometer is logged in g; pass accel_unit='g' "
            "(--accel-unit g)"
        )
    elif abs(median / g**2 - 1.0) <= UNIT_TOLERANCE and given == "g":
        hint = "about g²: the values were in m/s² already; drop accel_unit='g' (--accel-unit g)"
    elif median < 0.3 * g:
        hint = (
            "far below g: is it a linear acceleration with gravity removed? ftkin needs the raw "
            "specific force (an accelerometer at rest reads +g upward)"
        )
    else:
        hint = f"expected about g = {g:g} m/s² (or 1 in g); is it another unit?"
    raise InvalidSamples(
        f"the specific force's median norm is {median:.4g} m/s² (after the unit {given!r}): {hint}",
        source,
    )


@dataclass(frozen=True)
class ImuPoseAverages:
    """IMU readings averaged per static pose.

    Attributes:
        pose_ids: ``(P,)`` pose identifiers, in order of first appearance.
        specific_force: ``(P, 3)`` mean accelerometer reading [m/s², IMU frame].
        wrenches: ``(P, 6)`` mean raw wrench [N, N·m].
        counts: ``(P,)`` readings per pose.
        accel_spread: ``(P, 3)`` sample standard deviation of the accelerometer per pose [m/s²]
            (NaN for a single reading).
        wrench_spread: ``(P, 6)`` the same for the wrench [N, N·m].
        accel_count_factor: The samples' :attr:`ImuSamples.accel_count_factor`.
    """

    pose_ids: np.ndarray
    specific_force: np.ndarray
    wrenches: np.ndarray
    counts: np.ndarray
    accel_spread: np.ndarray
    wrench_spread: np.ndarray
    accel_count_factor: float = 1.0

    def __len__(self) -> int:
        return len(self.pose_ids)


@dataclass(frozen=True)
class ImuSamples:
    """Raw readings with the sensor's own IMU instead of an orientation.

    Attributes:
        specific_force: ``(N, 3)`` accelerometer readings [m/s², IMU frame], ``+g`` upward at
            rest (bias and scale errors included: the calibration estimates them).
        wrenches: ``(N, 6)`` raw readings, sensor frame [N, N·m].
        pose_ids: ``(N,)`` integer pose id of each reading (each its own pose when not given).
        angular_velocity: ``(N, 3)`` gyro readings [rad/s, IMU frame], or None.
        times: ``(N,)`` time of each reading [s], or None.
        g: Magnitude of gravity [m/s²] (the unit check and the sphere ``|a − b| = g``).
        accel_count_factor: Independent accelerometer readings per reading, in ``(0, 1]``: 1
            when each reading has its own; below when a slower IMU was interpolated onto the
            wrench's stamps (:func:`~ftkin.io.imu_columns.load_imu_samples` sets it: the rate
            ratio, times 2/3 for the spread that linear interpolation hides), so that the static
            fit weighs the accelerometer by what was measured, not by the rows it was spread
            over.
    """

    specific_force: np.ndarray
    wrenches: np.ndarray
    pose_ids: np.ndarray | None = None
    angular_velocity: np.ndarray | None = None
    times: np.ndarray | None = None
    g: float = STANDARD_GRAVITY
    accel_count_factor: float = 1.0

    def __post_init__(self):
        wrenches, _ = as_batch(self.wrenches, 6, "wrenches [fx, fy, fz, mx, my, mz]")
        try:
            check_wrench_magnitude(wrenches, "wrenches")
        except InvalidInput as error:
            raise InvalidSamples(str(error)) from None
        count = len(wrenches)
        if count == 0:
            raise InvalidSamples("no samples")
        force, _ = as_batch(self.specific_force, 3, "specific_force [ax, ay, az] (m/s²)")
        g = as_positive(self.g, "g")
        arrays = {"wrenches": wrenches, "specific_force": force}
        given = np.arange(count) if self.pose_ids is None else self.pose_ids
        try:
            arrays["pose_ids"] = as_integers(given, "pose ids")
        except InvalidInput as error:
            raise InvalidSamples(str(error)) from None
        if self.angular_velocity is not None:
            rates, _ = as_batch(self.angular_velocity, 3, "angular_velocity [wx, wy, wz] (rad/s)")
            fastest = float(np.max(np.abs(rates), initial=0.0))
            if fastest > MAX_ANGULAR_RATE:
                raise InvalidSamples(
                    f"the angular velocity reaches {fastest:.4g}: beyond {MAX_ANGULAR_RATE:g} "
                    "rad/s no wrist turns; is the gyro logged in °/s? (convert to rad/s)"
                )
            arrays["angular_velocity"] = rates
        if self.times is not None:
            times = as_float_array(self.times, "times [s]").reshape(-1)
            if not np.all(np.isfinite(times)):
                raise InvalidSamples("times must be finite [s]")
            check_time_span(times)
            arrays["times"] = times
        for name, array in arrays.items():
            if len(array) != count:
                raise InvalidSamples(
                    f"{count} wrenches but {len(array)} {name.replace('_', ' ')}; expected one each"
                )
        check_specific_force_unit(force, g)
        factor = as_real(self.accel_count_factor, "accel_count_factor")
        if not 0.0 < factor <= 1.0:
            raise InvalidInput(f"accel_count_factor must be in (0, 1], got {factor:g}")
        object.__setattr__(self, "accel_count_factor", factor)
        object.__setattr__(self, "g", g)
        for name, array in arrays.items():
            array = array.copy()  # frozen copies, never the caller's arrays
            array.setflags(write=False)
            object.__setattr__(self, name, array)

    def __len__(self) -> int:
        return len(self.wrenches)

    @classmethod
    def from_arrays(
        cls,
        specific_force,
        wrenches,
        pose_ids=None,
        *,
        accel_unit: str = "m/s^2",
        angular_velocity=None,
        times=None,
        g: float = STANDARD_GRAVITY,
    ) -> "ImuSamples":
        """From arrays in the user's accelerometer unit (``"m/s^2"`` or ``"g"``), checked."""
        g = check_gravity(g)
        factor = accel_unit_factor(accel_unit, g)
        force, _ = as_batch(specific_force, 3, "specific_force [ax, ay, az]")
        check_specific_force_unit(force * factor, g, accel_unit)
        return cls(force * factor, wrenches, pose_ids, angular_velocity, times, g)

    @property
    def is_static(self) -> bool:
        """True when readings share pose ids (static poses to average)."""
        return len(np.unique(self.pose_ids)) < len(self.pose_ids)

    def pose_averages(self) -> ImuPoseAverages:
        """Average the readings of each pose (vectorized).

        Raises:
            InvalidSamples: the specific force of one pose turns by more than 2° (the pose id
                groups readings of different poses, or the tool moved).
        """
        unique, first, inverse, counts = np.unique(
            self.pose_ids, return_index=True, return_inverse=True, return_counts=True
        )
        order = np.argsort(first)
        group, counts = np.argsort(order)[inverse], counts[order]

        def total(values: np.ndarray) -> np.ndarray:
            out = np.zeros((len(unique),) + values.shape[1:])
            np.add.at(out, group, values)
            return out

        force_means = total(self.specific_force) / counts[:, None]
        wrench_means = total(self.wrenches) / counts[:, None]
        with np.errstate(invalid="ignore", divide="ignore"):
            dof = counts[:, None] - 1
            accel_spread = np.sqrt(total((self.specific_force - force_means[group]) ** 2) / dof)
            wrench_spread = np.sqrt(total((self.wrenches - wrench_means[group]) ** 2) / dof)
        unit = self.specific_force / np.linalg.norm(self.specific_force, axis=1)[:, None]
        mean_unit = force_means / np.linalg.norm(force_means, axis=1)[:, None]
        angle = np.arccos(np.clip(np.einsum("ij,ij->i", unit, mean_unit[group]), -1.0, 1.0))
        worst = int(np.argmax(angle))
        if angle[worst] > MAX_POSE_SPREAD:
            raise InvalidSamples(
                f"the specific force of pose {self.pose_ids[worst]} turns by up to "
                f"{np.rad2deg(angle[worst]):.2f}° (more than {np.rad2deg(MAX_POSE_SPREAD):.0f}°): "
                "a pose id must group readings of one static pose; check the pose column, or, for "
                "poses found from the still phases of a recording, the time unit and the "
                "stillness thresholds (--speed-threshold, --settle-time; or use the moving "
                "recording's dynamic calibration)"
            )
        return ImuPoseAverages(
            unique[order],
            force_means,
            wrench_means,
            counts,
            accel_spread,
            wrench_spread,
            self.accel_count_factor,
        )
