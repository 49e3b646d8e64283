"""Where the bias of a :class:`~ftkin.control.compensation.Compensator` comes from, at run time.

The bias ``[F0, M0]`` [N, N·m] subtracted from every reading is an attribute
that these methods move without slowing the control path: a re-zero at a known
pose (keeping the tool weight), readings a driver zeroed at a pose, an attached
:class:`~ftkin.control.bias_tracker.BiasTracker`, and, for logs with times
inside a drifting calibration's recording, the calibration's bias trajectory.
"""

from __future__ import annotations

import numpy as np

from ..exceptions import InvalidInput
from ..validation import as_float_array, as_rotation_batch, as_vector


class BiasControl:
    """Bias methods of :class:`~ftkin.control.compensation.Compensator` (a mixin: it holds no state
    of its own).
    """

    @property
    def bias(self) -> np.ndarray:
        """The bias ``[F0, M0]`` [N, N·m] subtracted now (a copy)."""
        return self._bias.copy()

    def _apply_bias(self, bias: np.ndarray) -> None:
        self._bias = np.array(bias, dtype=float)
        self.refresh_floats()

    def set_bias(self, bias) -> None:
        """Use ``bias`` ``(6,)`` [N, N·m] from now on (the tracker, if any, restarts from it)."""
        bias = as_vector(bias, 6, "bias [F0, M0]")
        self._apply_bias(bias)
        if self.tracker is not None:
            self.tracker.reset(bias)

    def rezero_rotation(self, rotation_sensor_to_base, raw_wrench) -> np.ndarray:
        """:meth:`rezero` from ``R_BS`` ``(3, 3)``; returns the new bias ``(6,)``."""
        rotations, _ = as_rotation_batch(rotation_sensor_to_base)
        raw = as_vector(raw_wrench, 6, "raw_wrench")
        if len(rotations) != 1:
            raise InvalidInput("rezero takes one (3, 3) rotation")
        if (
            self._reading_signs is not None
        ):  # a stored sensor sign or reversed axis applies to this reading too
            raw = raw * self._reading_signs
        bias = raw - self.calibration.tool_gravity_wrench(rotations[0])
        self.set_bias(bias)
        return bias

    def rezero(self, q, raw_wrench) -> np.ndarray:
        """Re-zero at joint angles ``q`` [rad]: the contact wrench of ``raw_wrench`` becomes zero.

        The new bias is the reading minus the predicted tool gravity at ``q``
        (not the whole reading, which would subtract the tool's weight at
        this pose and make it appear at every other). The tool must be free
        of contact and the arm still. Returns the new bias ``(6,)`` [N, N·m].
        """
        arm = self._require_arm()
        q = as_vector(q, arm.nq, "q")
        return self.rezero_rotation(arm.sensor_rotation_unchecked(q), raw_wrench)

    def driver_zeroed_at_rotation(self, rotation_sensor_to_base) -> np.ndarray:
        """:meth:`driver_zeroed_at` from ``R_BS`` ``(3, 3)``; returns the new bias ``(6,)``."""
        rotations, _ = as_rotation_batch(rotation_sensor_to_base)
        if len(rotations) != 1:
            raise InvalidInput("driver_zeroed_at takes one (3, 3) rotation")
        bias = -self.calibration.tool_gravity_wrench(rotations[0])
        self.set_bias(bias)
        return bias

    def driver_zeroed_at(self, q0) -> np.ndarray:
        """The sensor driver was zeroed (tool on, no contact) at joint angles ``q0`` [rad].

        Its readings are then ``raw − raw(q0)``: the true bias and the tool
        gravity at ``q0`` are gone. The bias to subtract from them is minus the
        tool gravity wrench at ``q0`` (``−[Gs(q0), P × Gs(q0)]``), after which
        the contact wrenches are right at every pose. Returns that bias ``(6,)``.
        """
        arm = self._require_arm()
        q0 = as_vector(q0, arm.nq, "q0")
        return self.driver_zeroed_at_rotation(arm.sensor_rotation_unchecked(q0))

    def bias_at(self, times) -> np.ndarray:
        """Bias ``(N, 6)`` [N, N·m] for readings at ``times`` ``(N,)`` [s].

        Inside the recording of a drifting calibration: its trajectory
        (:meth:`~ftkin.calibration.drift.BiasDrift.bias_at`). Outside it (after
        its end, or before its start, e.g. a log on another clock), or without
        a drift model: the current bias (calibration's last, or as re-zeroed
        or tracked since).
        """
        times = as_float_array(times, "times").reshape(-1)
        out = np.tile(self._bias, (len(times), 1))
        drift = self.calibration.drift
        if drift is not None and drift.model != "none":
            inside = drift.covers(times)
            out[inside] = drift.bias_at(times[inside])
        return out

    def compensate_tracked(
        self, q, raw_wrench, dt: float, *, free: bool | None = None
    ) -> np.ndarray:
        """:meth:`compensate`, then feed the tracker (if any) with the result; see
        :meth:`observe_bias`.
        """
        contact = self.compensate(q, raw_wrench)
        self.observe_bias(contact, dt, q=q, free=free)
        return contact

    def observe_bias(
        self, contact_wrench, dt: float, *, q=None, free: bool | None = None, fault: bool = False
    ) -> bool:
        """Give the tracker this tick's contact wrench; True when it moved the bias (used from the
        next call).
        """
        tracker = self.tracker
        if tracker is None or not tracker.observe(contact_wrench, dt, q=q, free=free, fault=fault):
            return False
        self._apply_bias(tracker.bias)
        return True
