"""Which axes a static tool's wrench was recorded in, judged from the data: sensor or base.

The weight of a static tool is a fixed vector in base axes. Read in the sensor frame it turns with
the sensor, ``F = R_BSᵀ a + F0``; read in base axes it stays put and the bias turns instead,
``F_B = a + R_BS F0``. A driver whose wrench comes in base axes (UR's ``ft_raw_wrench``) is turned
into the sensor frame, ``F_S = R_BSᵀ F_B`` (and the torques alike), before calibration; the wrong
choice fits poorly, or fits a tool that weighs nothing.

:func:`check_wrench_frame` takes readings already in the sensor frame under the assumption
``wrench_frame`` and fits the paper's linear model
(:func:`~ftkin.calibration.linear.fit_linear`) to them as given and under the other assumption:
the rotation undone (``R_BS W``, for ``"base"``) or applied (``R_BSᵀ W``, for ``"sensor"``). The
verdict follows :func:`~ftkin.calibration.doctor.diagnose_readings`' rules (the one
``ftkin doctor`` uses to catch a base-frame wrench): the other assumption is the mistake when its
chi-square is at least :data:`~ftkin.calibration.doctor.MISTAKE_RATIO` times smaller, or when as
given the tool weighs almost nothing. Poses that cannot tell (fewer than three, or orientations
that do not turn the weight) give ``"undetermined"``, not a refusal.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..exceptions import ConventionMistake, InvalidInput
from .doctor import ConventionReport, Reading, diagnose_readings
from .samples import PoseAverages, Samples

WRENCH_FRAMES = ("base", "sensor")
"""The assumptions: the driver's wrench came in base axes (turned here) or in the sensor's."""


@dataclass(frozen=True)
class WrenchFrameCheck:
    """What the data say about the frame their wrench was recorded in.

    Attributes:
        wrench_frame: The assumption the readings were converted under.
        verdict: ``"ok"``, ``"suspect"`` (warn), ``"mistake"`` (refuse) or ``"undetermined"``.
        report: The fits of both assumptions (:class:`~ftkin.calibration.doctor.ConventionReport`).
        fix: The option to change when the verdict is not ok, e.g. ``--wrench-frame sensor``.
    """

    wrench_frame: str
    verdict: str
    report: ConventionReport
    fix: str

    @property
    def other_frame(self) -> str:
        """The assumption the check compares against."""
        return WRENCH_FRAMES[1 - WRENCH_FRAMES.index(self.wrench_frame)]

    @property
    def message(self) -> str:
        """One sentence: what fits, and the option to change."""
        if self.verdict in ("ok", "undetermined"):
            return f"the wrench frame {self.wrench_frame!r} is consistent: {self.report.reason}"
        return (
            f"the readings fit a wrench recorded in {self.other_frame} axes, not in "
            f"{self.wrench_frame} axes ({self.report.reason}): read it with {self.fix}"
        )


def _rotated(poses: PoseAverages, undo: bool) -> PoseAverages:
    """The pose wrenches with ``R_BS`` (``undo``) or ``R_BSᵀ`` applied to force and torque."""
    pattern = "nij,nkj->nki" if undo else "nji,nkj->nki"
    wrenches = np.einsum(pattern, poses.rotations, poses.wrenches.reshape(-1, 2, 3))
    return replace(poses, wrenches=wrenches.reshape(-1, 6))


def check_wrench_frame(
    samples: Samples | PoseAverages,
    wrench_frame: str,
    *,
    flag: str = "--wrench-frame",
    raise_on_mistake: bool = True,
) -> WrenchFrameCheck:
    """Check, from recorded static poses, the frame their wrench was taken to be in.

    Args:
        samples: Readings in the sensor frame (converted under ``wrench_frame``) and their
            ``R_BS``; averaged per pose.
        wrench_frame: ``"base"`` (the driver's wrench was turned into the sensor frame) or
            ``"sensor"`` (taken as it came).
        flag: How the fix is named (``--wrench-frame`` on the command line; the library's
            keyword is ``wrench_frame=``).
        raise_on_mistake: Raise on the ``"mistake"`` verdict (else return it).

    Returns:
        The :class:`WrenchFrameCheck`.

    Raises:
        ConventionMistake: the data fit the other frame (the message names ``flag`` and its
            value), when ``raise_on_mistake``.
        InvalidInput: ``wrench_frame`` is not ``"base"`` or ``"sensor"``.
    """
    if wrench_frame not in WRENCH_FRAMES:
        raise InvalidInput(f"wrench_frame must be one of {WRENCH_FRAMES}, got {wrench_frame!r}")
    poses = samples.pose_averages() if isinstance(samples, Samples) else samples
    other = WRENCH_FRAMES[1 - WRENCH_FRAMES.index(wrench_frame)]
    fix = f"{flag} {other}" if flag.startswith("-") else f"{flag}{other!r}"
    alternative = Reading(
        # doctor's own name for the base-frame reading: its "the tool weighs nothing" rule
        "the wrench in the base frame" if other == "base" else "the wrench in the sensor frame",
        f"read the wrench with {fix}",
        _rotated(poses, undo=wrench_frame == "base"),
    )
    report = diagnose_readings([Reading("as given", "", poses), alternative])
    check = WrenchFrameCheck(wrench_frame, report.verdict, report, fix)
    if raise_on_mistake and check.verdict == "mistake":
        raise ConventionMistake(check.message, reading=alternative.name, fix=fix)
    return check
