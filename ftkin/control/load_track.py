"""A recording's load, row by row: :func:`track_load` runs a :class:`LoadTracker` over it.

What ``ftkin compensate --track-load`` writes: per row the contact after the tool and the load,
the load's mass and COM with the mass's standard error, and the row's label (state or event).
"""

from dataclasses import dataclass

import numpy as np

from ..exceptions import InvalidInput
from ..validation import as_float_array, as_rotation_batch, as_wrenches
from .load_events import LoadEvent, LoadTracker

GRIPPER_COLUMN, GRIPPER_STATES = "gripper", "1 (gripper closed) or 0 (open)"
"""A log's gripper column and what its cells hold (read by
:meth:`~ftkin.io.csv_table.Table.booleans` into :func:`track_load`'s ``gripper``)."""


@dataclass(frozen=True)
class LoadTrack:
    """Per-row results of :func:`track_load` (``N`` rows).

    Attributes:
        contact: ``(N, 6)`` contact wrench after the tool and the load, sensor frame [N, N·m].
        mass: ``(N,)`` the held load's mass [kg] (0 when empty).
        mass_std: ``(N,)`` its standard error [kg] (0 when empty).
        com_in_sensor: ``(N, 3)`` its centre of mass, sensor frame [m]; NaN when empty or for a
            component the rows so far do not determine (along gravity before the wrist turned).
        labels: ``(N,)`` each row's label (:data:`~ftkin.control.load_events.LABELS`).
        events: The tracker's :class:`~ftkin.control.load_events.LoadEvent` list.
    """

    contact: np.ndarray
    mass: np.ndarray
    mass_std: np.ndarray
    com_in_sensor: np.ndarray
    labels: tuple[str, ...]
    events: tuple[LoadEvent, ...]

    def __post_init__(self):
        for name in ("contact", "mass", "mass_std", "com_in_sensor"):
            value = np.array(getattr(self, name), dtype=float)
            value.setflags(write=False)
            object.__setattr__(self, name, value)


def track_load(
    tracker: LoadTracker, rotations, contact_wrenches, times=None, gripper=None
) -> LoadTrack:
    """Run ``tracker`` over a recording, one tick per row.

    Args:
        tracker: A :class:`LoadTracker` (continued from its state; :meth:`~LoadTracker.reset`
            it for a new recording).
        rotations: ``R_BS`` ``(N, 3, 3)``.
        contact_wrenches: ``(N, 6)`` the contact after the tool (``Compensator.compensate_batch``)
            [N, N·m].
        times: ``(N,)`` reading times [s], increasing (default: the tracker's period apart).
        gripper: ``(N,)`` the gripper's state per row (True closed, False open), or None.

    Raises:
        InvalidInput: shapes that disagree, a time that is not finite or goes back.
    """
    rotations, _ = as_rotation_batch(rotations)
    contact, _ = as_wrenches(contact_wrenches, "contact_wrenches")
    count = len(contact)
    if len(rotations) != count:
        raise InvalidInput(f"{len(rotations)} rotations but {count} wrenches; expected one each")
    if times is not None:
        times = as_float_array(times, "times [s]").reshape(-1)
        if len(times) != count or not np.all(np.isfinite(times)):
            raise InvalidInput(f"times must be {count} finite numbers of seconds")
        if count > 1 and np.any(np.diff(times) < 0):
            raise InvalidInput("times must not go back: sort the log by its time column")
        times = times.tolist()
    if gripper is not None:
        gripper = np.asarray(gripper)
        if gripper.shape != (count,) or gripper.dtype != bool:
            raise InvalidInput(
                f"gripper must be {count} booleans (True closed, False open), got "
                f"{gripper.dtype} of shape {gripper.shape}"
            )
        gripper = gripper.tolist()
    out = np.empty((count, 6))
    mass, mass_std = np.zeros(count), np.zeros(count)
    com = np.full((count, 3), np.nan)
    labels = []
    version, current = None, (0.0, 0.0, np.full(3, np.nan))
    rows, values = rotations.tolist(), contact.tolist()
    for i in range(count):
        out[i] = tracker.tick(
            rows[i],
            values[i],
            None if times is None else times[i],
            None if gripper is None else gripper[i],
        )
        labels.append(tracker.label)
        if tracker.version != version:  # the estimate changed: its standard errors, off the tick
            version, estimate = tracker.version, tracker.estimate()
            current = (
                (0.0, 0.0, np.full(3, np.nan))
                if estimate is None
                else (estimate.mass, estimate.mass_std, estimate.com_in_sensor)
            )
        mass[i], mass_std[i], com[i] = current
    return LoadTrack(out, mass, mass_std, com, tuple(labels), tuple(tracker.events))
