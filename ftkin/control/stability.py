"""How large K1 may be: the discrete closed loop of the admittance law on a contact.

One axis, the tool pressing a spring–damper surface (stiffness ``k`` [N/m],
damping ``c`` [N·s/m]), the arm following the commanded velocity exactly
(``x[n+1] = x[n] + dt·V[n]``, ``x`` the penetration [m]). The surface pushes
back with ``N[n] = k·x[n] + c·(x[n] − x[n−1])/dt``; the controller sees it
``delay_ticks`` ticks late (``ΔF[n] = −N[n − d]`` plus constants) and runs
:meth:`~ftkin.control.admittance.Admittance.update`::

    D[n] = D[n−1] + α·((ΔF[n] − ΔF[n−1])/dt − D[n−1]),   α = 1 − exp(−2π f_c dt)
    V[n] = K1·D[n] + K2·ΔF[n]

The state ``(x[n], …, x[n−d−1], D[n−1])`` advances by a constant matrix ``A``
(companion form); the loop is stable when every eigenvalue of ``A`` lies inside
the unit circle. :func:`max_stable_k1` finds the K1 where the spectral radius
reaches 1. Saturation, the deadband and lifting off the surface are left out
(they bound an unstable loop into a limit cycle: chatter, not divergence).

With a one-tick delay (``d = 1``), 20 kN/m, 100 N·s/m and ``K2`` = 1 mm/(s·N):
0.26 mm/N at 1 kHz with a 5 Hz filter, 0.13 mm/N with 10 Hz, 0.11 mm/N at
100 Hz with 5 Hz.

Not in the model: the payload's inertia. The sensor also feels ``m·a`` of the
gripper and object, and K1 feeds it back; with an arm that followed commands
instantly that loop would limit K1 to a few µm/N at 1 kHz. A real arm's servo
filters the commanded velocity, which breaks that loop at high frequency; the
MuJoCo simulation (:mod:`ftkin.sim.mujoco`, servos of 60 Hz) shows where it
bites: a K1 of about 0.5 mm/N oscillates in free air with the paper's 0.55 kg payload.
"""

import math

import numpy as np

from ..exceptions import InvalidInput

MAX_DELAY_TICKS = 1000
"""Longest sensor delay :func:`max_stable_k1` takes [ticks] (the state grows by one per tick)."""


def derivative_alpha(dt: float, cutoff: float) -> float:
    """The exact discretisation ``α = 1 − exp(−dt/τ)``, ``τ = 1/(2π f_c)``, of a first-order
    low-pass [dt in s, cutoff in Hz].
    """
    return -math.expm1(-2.0 * math.pi * cutoff * dt)


def loop_matrix(
    k1: float,
    stiffness: float,
    damping: float,
    dt: float,
    cutoff: float,
    k2: float = 0.0,
    delay_ticks: int = 0,
) -> np.ndarray:
    """The state-transition matrix ``A`` of the linear loop (see the module docstring).

    State ``s[n] = (x[n], x[n−1], …, x[n−d−2], D[n−1])`` (``d + 4`` entries);
    ``s[n+1] = A s[n]``.
    """
    d = int(delay_ticks)
    # The loop is linear: each row below is one entry of A s for the unit states s (the columns).
    state = np.eye(d + 4)
    x, filtered = state[: d + 3], state[d + 3]
    error = -(stiffness * x[d] + damping * (x[d] - x[d + 1]) / dt)  # -N[n-d]
    error_before = -(stiffness * x[d + 1] + damping * (x[d + 1] - x[d + 2]) / dt)  # -N[n-d-1]
    derivative = filtered + derivative_alpha(dt, cutoff) * ((error - error_before) / dt - filtered)
    return np.vstack([x[0] + dt * (k1 * derivative + k2 * error), x[: d + 2], derivative])


def servo_loop_matrix(
    k1: float,
    stiffness: float,
    damping: float,
    dt: float,
    cutoff: float,
    k2: float = 0.0,
    delay_ticks: int = 0,
    servo_bandwidth: float = 60.0,
    mass: float = 0.0,
) -> np.ndarray:
    """The loop with a servoed arm and a payload (see :func:`max_stable_k1`'s ``servo_bandwidth``).

    The commanded velocity ``V`` (held over a tick) integrates into a position
    target ``r``; the tool follows it through a critically damped servo of
    natural frequency ``ω = 2π·servo_bandwidth``: ``p̈ = ω²(r − p) − 2ω ṗ``.
    The sensor feels ``N = k p + c ṗ + m p̈`` at each tick. Continuous state
    ``z = (r, p, ṗ)`` discretised exactly (zero-order hold on ``V``).
    State ``s[n] = (z[n], N[n−1], …, N[n−d−1], D[n−1])``.
    """
    from scipy.linalg import expm

    d, omega = int(delay_ticks), 2.0 * math.pi * servo_bandwidth
    square = omega * omega
    # (r, p, ṗ, V): dr/dt = V, dp/dt = ṗ, dṗ/dt = ω²(r − p) − 2ω ṗ, V held
    continuous = [[0, 0, 0, 1], [0, 0, 1, 0], [square, -square, -2.0 * omega, 0], [0, 0, 0, 0]]
    discrete = expm(np.array(continuous, dtype=float) * dt)
    felt = np.array([mass * square, stiffness - mass * square, damping - 2.0 * omega * mass])
    # The loop is linear: each row below is one entry of A s for the unit states s (the columns).
    state = np.eye(d + 5)
    z, filtered = state[:3], state[-1]
    forces = np.vstack([felt @ z, state[3 : 4 + d]])  # N[n], N[n-1], ..., N[n-d-1]
    error, error_before = -forces[d], -forces[d + 1]
    derivative = filtered + derivative_alpha(dt, cutoff) * ((error - error_before) / dt - filtered)
    velocity = k1 * derivative + k2 * error
    return np.vstack(
        [discrete[:3, :3] @ z + np.outer(discrete[:3, 3], velocity), forces[: d + 1], derivative]
    )


def spectral_radius(
    k1: float,
    stiffness: float,
    damping: float,
    dt: float,
    cutoff: float,
    k2: float = 0.0,
    delay_ticks: int = 0,
    servo_bandwidth: float | None = None,
    mass: float = 0.0,
) -> float:
    """Largest ``|eigenvalue|`` of :func:`loop_matrix` (or :func:`servo_loop_matrix`) (< 1: stable).

    With ``k2 = 0`` (or no spring) the tool may rest anywhere: a constant
    penetration is a fixed point, an eigenvalue exactly 1 for every K1. That
    neutral mode is left out (the one eigenvalue nearest 1).
    """
    eigenvalues = np.linalg.eigvals(
        loop_matrix(k1, stiffness, damping, dt, cutoff, k2, delay_ticks)
        if servo_bandwidth is None
        else servo_loop_matrix(
            k1, stiffness, damping, dt, cutoff, k2, delay_ticks, servo_bandwidth, mass
        )
    )
    if k2 == 0.0 or stiffness == 0.0:
        eigenvalues = np.delete(eigenvalues, int(np.argmin(np.abs(eigenvalues - 1.0))))
    return float(np.abs(eigenvalues).max())


def max_stable_k1(
    stiffness: float,
    damping: float,
    dt: float,
    cutoff: float,
    *,
    k2: float = 0.0,
    delay_ticks: int = 1,
    servo_bandwidth: float | None = None,
    mass: float = 0.0,
    upper: float = 1.0,
) -> float:
    """The K1 [m/N] at which the loop of the module docstring becomes unstable.

    Args:
        stiffness: Contact stiffness ``k`` [N/m] (the surface in series with the gripper and
            object); 0 (with ``damping`` 0) for free air.
        damping: Contact damping ``c`` [N·s/m].
        dt: Control period [s].
        cutoff: Derivative filter cutoff [Hz] (``Admittance.derivative_cutoff``).
        k2: Velocity gain K2 [m/(s·N)] used with it.
        delay_ticks: Ticks between the contact force and the controller seeing it (beyond the
            one tick the command needs to act); 1 for a sensor read at the start of the tick
            and used in the next, as :class:`~ftkin.sim.mujoco.MujocoSensor` does by default.
        servo_bandwidth: None: the arm follows the command exactly (the model above). A number
            [Hz]: the arm follows through a critically damped position servo of that natural
            frequency (:func:`servo_loop_matrix`, as :mod:`ftkin.sim.mujoco` builds them), and
            ``mass`` counts.
        mass: Payload beyond the sensor [kg] (gripper and object): the sensor feels its ``m·a``,
            which K1 feeds back. With ``stiffness = damping = 0`` this gives the free-air limit.
        upper: Search no further than this K1 [m/N]; returned if the loop is still stable there.

    Returns:
        The smallest K1 ≥ 0 with spectral radius ≥ 1 (to a relative 1e-6), ``0.0`` if even K1 = 0
        is unstable (K2 too large for this contact and rate).

    Raises:
        InvalidInput: a non-positive stiffness, period or cutoff, a negative damping, gain or delay.
    """
    real = lambda v: isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
    servo_ok = (
        servo_bandwidth is None
        and mass == 0
        or servo_bandwidth is not None
        and real(servo_bandwidth)
        and servo_bandwidth > 0
    )
    if not (
        all(real(v) and v > 0 for v in (dt, cutoff, upper))
        and all(real(v) and v >= 0 for v in (stiffness, damping, k2, mass))
        and servo_ok
        and stiffness + damping + (mass if servo_bandwidth is not None else 0.0) > 0  # felt
        and isinstance(delay_ticks, int)
        and not isinstance(delay_ticks, bool)
        and 0 <= delay_ticks <= MAX_DELAY_TICKS
    ):
        raise InvalidInput(
            "max_stable_k1 needs dt, cutoff > 0; stiffness, damping, k2, mass >= 0, something felt "
            "(k, c, or m "
            "with a servo_bandwidth > 0; mass needs a servo_bandwidth) and an integer delay_ticks "
            f"0..{MAX_DELAY_TICKS}; got "
            f"k={stiffness!r}, c={damping!r}, dt={dt!r}, cutoff={cutoff!r}, k2={k2!r}, "
            f"delay_ticks={delay_ticks!r}, "
            f"servo_bandwidth={servo_bandwidth!r}, mass={mass!r}"
        )
    radius = lambda k1: spectral_radius(
        k1, stiffness, damping, dt, cutoff, k2, delay_ticks, servo_bandwidth, mass
    )
    if radius(0.0) >= 1.0:
        return 0.0
    # scan up in factors of 1.25 from a tiny gain (the radius need not be monotonic far past the
    # bound), then bisect
    low, high = 0.0, upper * 1e-9
    while radius(high) < 1.0:
        if high == upper:
            return upper
        low, high = high, min(high * 1.25, upper)
    while high - low > 1e-6 * high:
        middle = 0.5 * (low + high)
        low, high = (middle, high) if radius(middle) < 1.0 else (low, middle)
    return 0.5 * (low + high)
