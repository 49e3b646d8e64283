"""Can a pose set determine the calibration parameters? (METHOD.md §3)

* ``gravity_in_base`` and ``force_offset`` need sensor orientations that are
  not all alike, and not all related by a rotation about gravity only.
* ``center_of_mass`` needs gravity seen along at least two non-parallel sensor
  directions (three distinct gravity directions in the sensor frame).

Both are checked on the column-normalized regressors of the two linear steps:
a relative singular value below :data:`MIN_RELATIVE_SINGULAR_VALUE` means the
poses leave a direction of the parameters undetermined, and the error names the
parameters that direction involves.
"""

import numpy as np

from ..exceptions import UnobservableParameters
from .covariance import check_determined
from .model import skew

MIN_POSES = 3
"""Fewest distinct static poses a calibration accepts."""

MIN_RELATIVE_SINGULAR_VALUE = 1e-3
"""Smallest accepted singular value of a normalized regressor, relative to the
largest (about the smallest angle, in radians, by which the poses must differ)."""

FORCE_STEP_NAMES = tuple(
    f"{name}[{axis}]" for name in ("gravity_in_base", "force_offset") for axis in "xyz"
)
TORQUE_STEP_NAMES = tuple(
    f"{name}[{axis}]" for name in ("center_of_mass", "torque_offset") for axis in "xyz"
)


def _beside_identity(blocks: np.ndarray) -> np.ndarray:
    """``[B_i  I]`` stacked, ``(3N, 6)``, from blocks ``(N, 3, 3)``."""
    return np.concatenate([blocks, np.broadcast_to(np.eye(3), blocks.shape)], axis=2).reshape(-1, 6)


def force_regressor(rotations: np.ndarray) -> np.ndarray:
    """Step-1 regressor ``[R_iᵀ  I]`` stacked, ``(3N, 6)``, for ``[a; F0]``."""
    return _beside_identity(np.transpose(rotations, (0, 2, 1)))


def torque_regressor(forces: np.ndarray) -> np.ndarray:
    """Step-2 regressor ``[-[F_i]×  I]`` stacked, ``(3N, 6)``, for ``[P; b]``."""
    return _beside_identity(-skew(forces))


def _check_rank(regressor: np.ndarray, names: tuple[str, ...], reason: str) -> None:
    """Refuse a regressor that leaves a direction open; the error names the parameter groups
    (``"gravity_in_base"``, ...) and carries the components' combination."""
    try:
        check_determined(regressor, names, reason, MIN_RELATIVE_SINGULAR_VALUE)
    except UnobservableParameters as error:
        groups = sorted({name.split("[")[0] for name in error.names})
        raise UnobservableParameters(
            groups, error.reason, error.singular_values, error.combination
        ) from None


def check_pose_count(pose_count: int) -> None:
    """Refuse fewer than :data:`MIN_POSES` poses."""
    if pose_count < MIN_POSES:
        raise UnobservableParameters(
            ["gravity_in_base", "force_offset", "torque_offset", "center_of_mass"],
            f"only {pose_count} distinct pose(s); at least {MIN_POSES} static poses with "
            "different orientations are needed",
        )


def check_orientations(rotations: np.ndarray) -> None:
    """Refuse pose orientations that cannot separate gravity from the force bias."""
    _check_rank(
        force_regressor(rotations),
        FORCE_STEP_NAMES,
        "the sensor orientations are all alike (or differ only by rotations about one axis), "
        "so the tool's weight cannot be told apart from the force bias; tilt the sensor about "
        "at least two different axes",
    )


def check_gravity_directions(rotations: np.ndarray, gravity_in_base: np.ndarray) -> None:
    """Refuse poses in which gravity is seen along one sensor direction only."""
    weight = np.linalg.norm(gravity_in_base)
    if weight == 0.0:
        raise UnobservableParameters(
            ["center_of_mass"],
            "the estimated tool weight is zero, so its centre of mass has no effect",
        )
    _check_rank(
        torque_regressor(np.transpose(rotations, (0, 2, 1)) @ (gravity_in_base / weight)),
        TORQUE_STEP_NAMES,
        "gravity is seen along one sensor direction only (poses differ only by rotation about "
        "the gravity axis); use at least three poses with "
        "gravity along different sensor directions",
    )
