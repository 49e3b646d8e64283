"""What every static problem of the accelerometer and the wrench declares (the shared fit reads).

The IMU fit (:class:`~ftkin.calibration.imu_problem.ImuStaticProblem`) and the fused fit
(:class:`~ftkin.calibration.fused_problem.FusedStaticProblem`) share their solver, their noise
estimates, their scale handling and their covariance (:mod:`ftkin.calibration.imu_fit`). Those
read the same members of either problem: the data fields of :data:`DATA_FIELDS`, the whitening
below (written once, here), and the model's methods, which each problem supplies. A problem class
that leaves a data field out fails when it is defined, one that leaves a method out when it is
built (not deep inside a fit, as the fused fit once did without ``channel_counts``).

Per pose ``i`` (readings averaged) the nine channels are ``[accelerometer (3) m/s², force (3)
N, torque (3) N·m]``, whitened by ``sqrt(n_ic) / σ_c`` with ``n_ic`` the independent readings of
channel ``c`` at pose ``i`` (the accelerometer's times ``accel_count_factor``).
"""

from abc import ABC, abstractmethod

import numpy as np

DATA_FIELDS = ("accel", "wrenches", "counts", "noise", "g", "scale_free", "accel_count_factor")
"""The data every problem holds: ``accel`` ``(P, 3)`` [m/s², IMU frame], ``wrenches`` ``(P, 6)``
[N, N·m], ``counts`` ``(P,)``, ``noise`` ``(9,)`` per reading, ``g`` [m/s²], ``scale_free`` (the
scale components estimated) and ``accel_count_factor`` (independent accelerometer readings per
reading, in ``(0, 1]``)."""


class NineChannelProblem(ABC):
    """A whitened least squares over ``(P, 9)`` accelerometer and wrench residuals.

    Subclasses are frozen dataclasses with the fields of :data:`DATA_FIELDS` (checked when the
    class is defined) and the model: :attr:`names`, :attr:`global_count`, :meth:`unpack`,
    :meth:`predict`, :meth:`jacobian` and :meth:`recentred` (checked when one is built).
    """

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        declared = set()
        for klass in cls.__mro__:
            declared |= set(vars(klass).get("__annotations__", {}))
        missing = [name for name in DATA_FIELDS if name not in declared]
        if missing:
            raise TypeError(
                f"{cls.__name__} must declare the data fields {', '.join(missing)} of a "
                "NineChannelProblem (ftkin.calibration.imu_problem_base.DATA_FIELDS)"
            )

    @property
    @abstractmethod
    def names(self) -> tuple[str, ...]:
        """The global parameters' names, in the order of ``x``."""

    @property
    @abstractmethod
    def global_count(self) -> int:
        """How many leading entries of ``x`` are global (the rest are per-pose nuisance)."""

    @property
    def parameter_count(self) -> int:
        """Length of ``x`` (the global parameters unless a subclass adds per-pose ones)."""
        return self.global_count

    @abstractmethod
    def unpack(self, x: np.ndarray) -> dict:
        """The parameters of ``x`` by name (``b`` the accelerometer bias, ``s`` its scale)."""

    @abstractmethod
    def predict(self, x: np.ndarray) -> np.ndarray:
        """``(P, 9)`` predicted ``[accel, F, M]`` per pose."""

    @abstractmethod
    def jacobian(self, x: np.ndarray) -> np.ndarray:
        """``(P, 9, n)`` derivative of :meth:`predict` with respect to ``x``."""

    @abstractmethod
    def recentred(self, x: np.ndarray) -> "tuple[NineChannelProblem, np.ndarray]":
        """The same problem with its reference rotations moved to ``x``, and ``x`` there."""

    @property
    def channel_counts(self) -> np.ndarray:
        """``(P, 9)`` independent readings per pose and channel (the accelerometer's times
        ``accel_count_factor``)."""
        factors = np.repeat([self.accel_count_factor, 1.0], [3, 6])
        return np.asarray(self.counts, dtype=float)[:, None] * factors[None, :]

    @property
    def weights(self) -> np.ndarray:
        """``(P, 9)`` whitening ``sqrt(n_ic) / σ_c``."""
        return np.sqrt(self.channel_counts) / self.noise[None, :]

    def residuals(self, x: np.ndarray) -> np.ndarray:
        """``(P, 9)`` measured minus predicted."""
        return np.concatenate([self.accel, self.wrenches], axis=1) - self.predict(x)

    def whitened_residuals(self, x: np.ndarray) -> np.ndarray:
        """``(9 P,)`` :meth:`residuals` times :attr:`weights`, flattened by pose."""
        return (self.residuals(x) * self.weights).reshape(-1)

    def whitened_jacobian(self, x: np.ndarray) -> np.ndarray:
        """``(9 P, n)`` :meth:`jacobian` of the prediction times :attr:`weights` (ftkin's one sign,
        :mod:`ftkin.calibration.covariance`; the residuals' derivative is its negative)."""
        return (self.jacobian(x) * self.weights[:, :, None]).reshape(-1, self.parameter_count)
