"""The arm a samples CSV was recorded on, written in it as a comment and checked when it is read.

``ftkin record`` writes what it knows of the arm as a ``#`` line (:func:`robot_comment`)::

    # robot: ur5e (the controller's dashboard: UR5 on URSoftware 5.15.0.12345)

above the header when it knows it before the first pose (``--robot``, the controller's
dashboard), or after the poses when the controller's TCP poses told it. A table read with an arm
of another ``--robot`` name, or with no arm (the bundled one) while the file names one, is
refused by :func:`check_recorded_robot` (called by
:func:`~ftkin.io.samples_csv.samples_from_table`), the message naming both: the static fit would
run, but the calibration would carry the wrong arm's kinematics. An arm from a URDF has no
``--robot`` name and is not compared (its URDF is the user's statement of the arm).
"""

from __future__ import annotations

import re

from ..exceptions import InvalidSamples

KEY = "robot:"
"""The comment's key."""
_LINE = re.compile(r"^robot:\s*([A-Za-z0-9_.-]+)\s*(?:\((.*)\))?\s*$")


def robot_comment(robot: str, source: str) -> str:
    """The comment line's text (without ``#``): ``robot: NAME (SOURCE)``."""
    return f"{KEY} {robot} ({source})"


def recorded_robots(comments) -> dict[str, str]:
    """``{robot name: how it was known}`` of a table's comment lines (``Table.comments``)."""
    found: dict[str, str] = {}
    for comment in comments:
        match = _LINE.match(comment.strip())
        if match is not None:
            found.setdefault(match.group(1), match.group(2) or "")
    return found


def check_recorded_robot(table, arm) -> None:
    """Refuse reading ``table`` with ``arm`` when the file names another ``--robot`` (module
    docstring); ``arm`` None stands for the bundled arm.

    Raises:
        InvalidSamples: the file names two arms, or another than ``arm``'s ``--robot`` name.
    """
    robots = recorded_robots(getattr(table, "comments", ()))
    if not robots:
        return
    if len(robots) > 1:
        named = "; ".join(f"{name} ({source})" for name, source in robots.items())
        raise InvalidSamples(
            f"its comments name more than one arm: {named}; keep the right '# {KEY}' line",
            table.source,
        )
    ((recorded, source),) = robots.items()
    if arm is not None and getattr(arm, "robot_name", None) is None:
        return  # a URDF: the user's own statement of the arm
    given = None if arm is None else arm.robot_name
    if given == recorded:
        return
    what = "no --robot (the bundled arm)" if given is None else f"--robot {given}"
    raise InvalidSamples(
        f"it was recorded on a {recorded} ({source}) but is read with {what}: give --robot "
        f"{recorded}",
        table.source,
    )
