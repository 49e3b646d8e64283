"""A pose plan written to a file (``ftkin plan -o POSES.csv|.yaml|.json``, or
:func:`write_plan` from Python): the same file whichever door writes it.

CSV: a ``pose`` column and one column per joint [rad], in visiting order (an input of ``ftkin
robot calibrate --poses`` and ``ftkin evaluate-poses``). YAML and JSON: :func:`plan_document`,
the joint names and positions [rad], the seed, the constraints, the criterion, the predicted
standard errors, the joint travel [rad] and, for a drift, its rate and the pose interval [s].
"""

import json
from pathlib import Path

import numpy as np

from ..exceptions import InvalidInput
from .atomic import atomic_write_text
from .csv_table import write_csv
from .samples_csv import POSE_COLUMN
from .yaml_text import yaml_text

PLAN_FORMATS = {"csv": (), "yaml": (".yaml", ".yml"), "json": (".json",)}
"""Formats of a written plan and the file name endings that choose them (any other: csv)."""


def plan_format(path, fmt: str | None = None) -> str:
    """The format a plan is written to ``path`` in: ``fmt`` when given, else the one its name's
    ending chooses (:data:`PLAN_FORMATS`), else csv.

    Raises:
        InvalidInput: ``fmt`` is not one of :data:`PLAN_FORMATS`.
    """
    if fmt is not None:
        if fmt not in PLAN_FORMATS:
            raise InvalidInput(f"plan format {fmt!r} is not one of {', '.join(PLAN_FORMATS)}")
        return fmt
    name = str(path).lower()
    return next(
        (f for f, endings in PLAN_FORMATS.items() if endings and name.endswith(endings)), "csv"
    )


def plan_document(plan) -> dict:
    """A :class:`~ftkin.planning.plan.PosePlan` as plain data (the YAML and JSON files)."""
    return {
        "joint_names": list(plan.joint_names),
        "joint_positions_rad": plan.joint_positions.tolist(),
        "seed": plan.seed,
        "constraints": plan.constraints.describe(),
        "criterion": plan.criterion,
        "criterion_value": plan.criterion_value,
        "predicted_standard_errors": {
            key: np.atleast_1d(value).tolist() for key, value in plan.standard_errors.items()
        },
        "joint_travel_rad": plan.joint_travel,
        **(
            {}
            if plan.evaluation.drift_rate is None
            else {
                "drift_rate": plan.evaluation.drift_rate.tolist(),
                "pose_interval_s": plan.evaluation.pose_interval,
            }
        ),
    }


def write_plan(plan, path, fmt: str | None = None) -> str:
    """Write a :class:`~ftkin.planning.plan.PosePlan` to ``path`` (atomically) as CSV, YAML or
    JSON (:func:`plan_format`); returns the format written."""
    fmt = plan_format(path, fmt)
    path = Path(path)
    if fmt == "csv":
        write_csv(
            path,
            [POSE_COLUMN, *plan.joint_names],
            [[i, *map(float, q)] for i, q in enumerate(plan.joint_positions)],
        )
    elif fmt == "json":
        atomic_write_text(path, json.dumps(plan_document(plan), indent=2) + "\n")
    else:
        atomic_write_text(path, yaml_text(plan_document(plan)))
    return fmt
