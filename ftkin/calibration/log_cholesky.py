"""Rigid-body inertial parameters, their pseudo-inertia and log-Cholesky coordinates.

The ten inertial parameters of a body in a frame S follow Pinocchio's
``Inertia.toDynamicParameters()`` order::

    θ = [m, m·cx, m·cy, m·cz, Ixx, Ixy, Iyy, Ixz, Iyz, Izz]

with ``m`` [kg], ``c`` the centre of mass in S [m] and ``I`` the rotational
inertia about S's origin in S's axes [kg·m²]. θ is physically consistent
(a real mass distribution) exactly when the 4×4 pseudo-inertia
``J = [[Σ, h], [hᵀ, m]]`` (``Σ = ½ tr(I)·1 − I``, ``h = m c``) is positive
definite (Wensing, Kim & Slotine 2017).

The log-Cholesky coordinates ``φ = [α, d1, d2, d3, s12, s23, s13, t1, t2, t3]``
(Rucker & Wensing 2022, the order of ``pin.LogCholeskyParameters``) write
``J = U Uᵀ`` with the upper-triangular ``U = e^α [[e^d1, s12, s13, t1],
[0, e^d2, s23, t2], [0, 0, e^d3, t3], [0, 0, 0, 1]]``: every real φ gives a
consistent θ and every consistent θ has one φ, so an unconstrained optimiser
over φ searches exactly the physically consistent bodies.
"""

import numpy as np
import pinocchio as pin

from ..exceptions import InvalidInput
from ..validation import as_vector

INERTIAL_PARAMETER_NAMES = ("m", "mcx", "mcy", "mcz", "Ixx", "Ixy", "Iyy", "Ixz", "Iyz", "Izz")
"""Names of the ten entries of θ (inertia about the frame origin)."""

_TRIANGLE = ((0, 0, 1, 0, 1, 2), (0, 1, 1, 2, 2, 2))  # rows, columns of [xx, xy, yy, xz, yz, zz]


def inertia_matrix(values6) -> np.ndarray:
    """Symmetric 3×3 matrix from ``[xx, xy, yy, xz, yz, zz]`` (Pinocchio's order)."""
    xx, xy, yy, xz, yz, zz = np.asarray(values6, dtype=float)
    return np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])


def inertia_entries(matrix) -> np.ndarray:
    """Inverse of :func:`inertia_matrix`: ``[xx, xy, yy, xz, yz, zz]`` of a 3×3 matrix."""
    return np.asarray(matrix, dtype=float)[_TRIANGLE]


def parameters_from_body(mass: float, center_of_mass, inertia_about_com) -> np.ndarray:
    """θ from mass [kg], COM [m] and the inertia about the COM (3×3) [kg·m²], all in frame S."""
    com = as_vector(center_of_mass, 3, "center_of_mass")
    inertia = pin.Inertia(float(mass), com, np.asarray(inertia_about_com, dtype=float))
    return np.asarray(inertia.toDynamicParameters(), dtype=float)


def body_from_parameters(theta) -> tuple[float, np.ndarray, np.ndarray]:
    """``(mass [kg], COM [m], inertia about the COM 3×3 [kg·m²])`` from θ.

    Raises:
        InvalidInput: the mass is not positive (the COM is then undefined).
    """
    theta = as_vector(theta, 10, "inertial parameters")
    mass = float(theta[0])
    if mass <= 0.0:
        raise InvalidInput(f"the mass in the inertial parameters must be positive, got {mass!r} kg")
    com = theta[1:4] / mass
    # Parallel-axis theorem: I_origin = I_com + m (|c|² 1 − c cᵀ).
    return (
        mass,
        com,
        inertia_matrix(theta[4:10]) - mass * (com @ com * np.eye(3) - np.outer(com, com)),
    )


def pseudo_inertia(theta) -> np.ndarray:
    """The 4×4 pseudo-inertia ``J`` of θ (``pin.PseudoInertia``)."""
    theta = as_vector(theta, 10, "inertial parameters")
    return np.asarray(pin.PseudoInertia.FromDynamicParameters(theta).toMatrix(), dtype=float)


def is_physically_consistent(theta, tolerance: float = 0.0) -> bool:
    """True when the pseudo-inertia's smallest eigenvalue exceeds ``tolerance`` [kg·m²]."""
    return bool(np.linalg.eigvalsh(pseudo_inertia(theta))[0] > tolerance)


def parameters_from_log_cholesky(phi) -> np.ndarray:
    """θ of log-Cholesky coordinates φ (``pin.LogCholeskyParameters``)."""
    phi = as_vector(phi, 10, "log-Cholesky parameters")
    return np.asarray(pin.LogCholeskyParameters(phi).toDynamicParameters(), dtype=float)


def log_cholesky_jacobian(phi) -> np.ndarray:
    """``∂θ/∂φ`` (10×10) at φ (Pinocchio's ``calculateJacobian``)."""
    phi = as_vector(phi, 10, "log-Cholesky parameters")
    return np.asarray(pin.LogCholeskyParameters(phi).calculateJacobian(), dtype=float)


def log_cholesky_from_parameters(theta) -> np.ndarray:
    """φ of a physically consistent θ (the inverse Pinocchio does not provide).

    ``J = U Uᵀ`` with ``U`` upper triangular is the ordinary Cholesky factor of
    ``E J E`` (``E`` the exchange matrix) flipped back: ``U = E L E``.

    Raises:
        InvalidInput: θ is not physically consistent (``J`` not positive definite).
    """
    pseudo = pseudo_inertia(theta)
    exchange = np.eye(4)[::-1]
    try:
        lower = np.linalg.cholesky(exchange @ pseudo @ exchange)
    except np.linalg.LinAlgError:
        raise InvalidInput(
            "the inertial parameters are not physically consistent (pseudo-inertia not positive "
            "definite); "
            f"its eigenvalues are {np.linalg.eigvalsh(pseudo).tolist()}"
        ) from None
    upper = exchange @ lower @ exchange
    u = upper / upper[3, 3]
    return np.array(
        [
            np.log(upper[3, 3]),
            np.log(u[0, 0]),
            np.log(u[1, 1]),
            np.log(u[2, 2]),
            u[0, 1],
            u[1, 2],
            u[0, 2],
            u[0, 3],
            u[1, 3],
            u[2, 3],
        ]
    )


def nearest_consistent(theta, floor: float = 1e-9) -> np.ndarray:
    """A physically consistent θ close to θ: the pseudo-inertia's eigenvalues clipped at ``floor`` ×
    its scale.

    Used to start the constrained fit when the unconstrained one is inconsistent.
    """
    values, vectors = np.linalg.eigh(pseudo_inertia(theta))
    scale = max(float(np.abs(values).max()), 1e-12)
    clipped = (vectors * np.maximum(values, floor * scale)) @ vectors.T
    sigma, h, mass = clipped[:3, :3], clipped[:3, 3], clipped[3, 3]
    return np.concatenate([[mass], h, inertia_entries(np.trace(sigma) * np.eye(3) - sigma)])
