"""A UR recording without its model: the flange orientation of any UR, and which UR it was.

The orientation of a UR's flange depends on the joint angles and the DH twists only, which every
UR arm shares (:func:`~ftkin.kinematics.ur_eseries.flange_rotation`): :class:`UrFlange` gives
``R_BS`` (the sensor at the flange, its axes) for the poses of a recording, enough to record them,
check their wrench frame and calibrate the static model, but it has no positions or masses (no
Jacobians, no dynamics, no kinematics record): a calibration still names its arm
(``ftkin calibrate --robot ur5e``).

Which arm it was, the controller's own poses say: ``actual_TCP_pose`` is the flange pose computed
with the controller's (factory-calibrated) kinematics, offset by the TCP set on the pendant,
``p_tcp = p_flange(q) + ᴮR_tool0(q) o``. :func:`identify_ur_arm` fits the offset ``o`` [m] by
least squares for each of ftkin's UR models and keeps the one whose positions fit: nominal and
factory-calibrated kinematics differ by about a millimetre, two UR sizes by decimetres.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..exceptions import InvalidInput
from .ur_eseries import FLANGE_FRAME, JOINT_NAMES, UR_DH, dh_model, flange_rotation

MATCH_RMS = 0.005
"""A model whose TCP positions fit within this RMS [m] is the arm (factory calibration moves the
flange by about 1 mm from the nominal model)."""
OTHER_RMS = 0.02
"""...and every other model must misfit by at least this RMS [m], else the poses do not tell the
models apart (too few, too alike)."""
MIN_IDENTIFYING_POSES = 3
"""Poses needed: the three offset coordinates take the first pose's positions."""


class UrFlange:
    """The orientation of any UR arm's flange, as a recorder's arm: ``joint_names``, ``nq`` and
    ``rotation_sensor_to_base`` (the sensor at ``tool0``, its axes); no positions."""

    joint_names = list(JOINT_NAMES)
    nq = 6
    robot_name = None

    def __repr__(self) -> str:
        return "UrFlange(any UR arm: the flange orientation only)"

    def rotation_sensor_to_base(self, q) -> np.ndarray:
        """``R_BS`` ``(3, 3)`` at ``q`` ``(6,)``, or ``(n, 3, 3)`` at ``(n, 6)`` [rad]."""
        q = np.asarray(q, dtype=float)
        if q.ndim == 2:
            return np.array([flange_rotation(row) for row in q])
        return flange_rotation(q)


@dataclass(frozen=True)
class UrIdentification:
    """Which UR model's kinematics reproduce the controller's TCP poses.

    Attributes:
        robot: The ``--robot`` name that fits, or None when none does or several do.
        rms: ``{robot name: RMS position misfit [m]}`` of every model, its TCP offset fitted.
        offset: ``(3,)`` the TCP offset of ``robot`` in the flange frame [m] (zeros without one).
        poses: Poses used.
    """

    robot: str | None
    rms: dict
    offset: np.ndarray
    poses: int

    def describe(self) -> str:
        """One line: the model and its fit, the runner-up's misfit; or why none."""
        ranked = sorted(self.rms, key=self.rms.get)
        figures = ", ".join(f"{name} {1e3 * self.rms[name]:.1f} mm" for name in ranked[:3])
        if self.robot is not None:
            return (
                f"the controller's TCP poses at {self.poses} poses fit {self.robot} (RMS misfit "
                f"{figures})"
            )
        return (
            f"the controller's TCP poses at {self.poses} poses do not single out a UR model "
            f"(RMS misfit {figures}; one within {1e3 * MATCH_RMS:g} mm and the others beyond "
            f"{1e3 * OTHER_RMS:g} mm needed)"
        )


@functools.cache
def _model(name: str):
    model = dh_model(UR_DH[name])
    return model, model.createData(), model.getFrameId(FLANGE_FRAME)


def flange_positions(name: str, joint_positions) -> np.ndarray:
    """``(n, 3)`` the flange (``tool0``) position in the base frame [m] of UR model ``name`` at
    ``joint_positions`` ``(n, 6)`` [rad] (UR's nominal DH parameters)."""
    model, data, frame = _model(name)
    out = []
    for q in np.asarray(joint_positions, dtype=float):
        pin.forwardKinematics(model, data, q)
        out.append(pin.updateFramePlacement(model, data, frame).translation.copy())
    return np.array(out).reshape(-1, 3)


def identify_ur_arm(joint_positions, tcp_poses) -> UrIdentification:
    """Which of ftkin's UR models the controller is, from ``actual_q`` ``(n, 6)`` [rad] and
    ``actual_TCP_pose`` ``(n, 6)`` (position [m], rotation vector [rad]) of ``n`` packages at
    different poses (module docstring; :data:`MATCH_RMS`, :data:`OTHER_RMS`).

    Raises:
        InvalidInput: arrays that are not ``(n, 6)`` finite values of the same ``n``.
    """
    q = np.asarray(joint_positions, dtype=float)
    tcp = np.asarray(tcp_poses, dtype=float)
    if q.ndim != 2 or q.shape[1:] != (6,) or tcp.shape != q.shape:
        raise InvalidInput(
            f"expected (n, 6) joint positions and (n, 6) TCP poses, got {q.shape} and {tcp.shape}"
        )
    if not (np.all(np.isfinite(q)) and np.all(np.isfinite(tcp))):
        raise InvalidInput("the joint positions and TCP poses must be finite")
    rotations = UrFlange().rotation_sensor_to_base(q).reshape(-1, 3, 3)
    stacked = rotations.reshape(-1, 3)  # (3n, 3): p_tcp - p_flange = R o, pose by pose
    rms, offsets = {}, {}
    for name in UR_DH:
        difference = (tcp[:, :3] - flange_positions(name, q)).reshape(-1)
        offset = np.linalg.lstsq(stacked, difference, rcond=None)[0]
        misfit = (stacked @ offset - difference).reshape(-1, 3)
        rms[name] = float(np.sqrt(np.mean(np.sum(misfit**2, axis=1))))
        offsets[name] = offset
    ranked = sorted(rms, key=rms.get)
    best, runner_up = ranked[0], ranked[1]
    found = (
        len(q) >= MIN_IDENTIFYING_POSES and rms[best] <= MATCH_RMS and rms[runner_up] >= OTHER_RMS
    )
    return UrIdentification(
        best if found else None, rms, offsets[best] if found else np.zeros(3), len(q)
    )
