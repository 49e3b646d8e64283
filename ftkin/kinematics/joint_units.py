"""Joint angles given in degrees where radians are expected: one rule for every door.

``Samples.from_joint_positions``, a samples CSV's joint columns, a motion recording,
:meth:`~ftkin.control.compensation.Compensator.compensate` and the control tick all take ``q`` in
radians. Degrees are recognised without guessing, in two ways:

* a value beyond ``±2π`` (:data:`RADIANS_BOUND`): no revolute joint reports it in radians;
* otherwise (every ``|q| ≤ 2π``), a value more than :data:`DEGREES_LIMIT_EXCESS` (0.5 rad)
  outside the arm's limits while every value read as degrees lies within them: the limits
  decide. No robot stands that far past its URDF's limits (encoder overshoot and a URDF a
  little narrower than its robot are hundredths of a radian: such values are warned, not
  refused, by the samples' check; the control path refuses anything beyond
  :data:`JOINT_LIMIT_MARGIN`).

Small angles within the limits either way (a robot that barely moved, all ``|q|`` a few
degrees) cannot be told apart and are taken as radians; a pose set so close to the zero
configuration is also a poor calibration (``ftkin doctor`` fits it both ways).
"""

import numpy as np

RADIANS_BOUND = 2.0 * np.pi + 0.01
"""Largest ``|q|`` [rad] taken as radians (2π and a rounding margin)."""
JOINT_LIMIT_MARGIN = 0.05
"""How far past its URDF limit a joint angle is still taken as measured [rad or m] (encoder
overshoot at a hard stop); beyond it, ``q`` is refused (degrees, a wrong joint order)."""
DEGREES_LIMIT_EXCESS = 0.5
"""How far outside its limits [rad] a joint angle of a set that fits the limits as degrees is
taken for degrees."""
DEGREES_ADVICE = "joint angles must be in radians (these look like degrees: multiply by π/180)"
"""The end of every refusal of degrees: what to do."""


def degrees_for_radians(arm, q, names=None, what: str = "joint") -> tuple[int, int, str] | None:
    """The first joint angle of ``q`` ``(N, nq)`` [rad] that shows it holds degrees, as
    ``(row, column, message)``, or None (see the module docstring for the rule).

    ``arm``: its ``lower_limits``/``upper_limits`` (None: the ``±2π`` rule alone); ``names``:
    what to call each column (default: the arm's joint names, else ``q1..qn``); ``what``: the
    noun before a name (``"joint column"`` for a file).
    """
    q = np.asarray(q, dtype=float)
    q = q.reshape(1, -1) if q.ndim == 1 else q
    if names is None:
        names = list(arm.joint_names) if arm is not None else []
        names += [f"q{i + 1}" for i in range(len(names), q.shape[1])]
    beyond = np.argwhere(np.abs(q) > RADIANS_BOUND)
    if beyond.size:
        row, column = (int(i) for i in beyond[0])
        text = f"{what} {names[column]!r} holds {q[row, column]:g}, outside ±2π: {DEGREES_ADVICE}"
        return row, column, text
    if arm is None:
        return None
    lower, upper = np.asarray(arm.lower_limits, float), np.asarray(arm.upper_limits, float)
    if lower.shape != (q.shape[1],):
        return None
    outside = ~((q >= lower - DEGREES_LIMIT_EXCESS) & (q <= upper + DEGREES_LIMIT_EXCESS))
    as_degrees = np.deg2rad(q)
    within = (as_degrees >= lower - JOINT_LIMIT_MARGIN) & (as_degrees <= upper + JOINT_LIMIT_MARGIN)
    if not outside.any() or not np.all(within):
        return None
    row, column = (int(i) for i in np.argwhere(outside)[0])
    text = (
        f"{what} {names[column]!r} holds {q[row, column]:g}, more than "
        f"{DEGREES_LIMIT_EXCESS:g} rad outside its limits [{lower[column]:.4g}, "
        f"{upper[column]:.4g}] rad, and every angle read as degrees is within them: "
        f"{DEGREES_ADVICE}"
    )
    return row, column, text
