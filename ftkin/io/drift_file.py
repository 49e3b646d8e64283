"""The ``drift`` entry of a calibration file (format version 2): the bias trajectory.

The common keys are written here; each drift model writes and reads its own
(:meth:`~ftkin.calibration.drift.DriftModel.to_document`), and the model name is
looked up in the drift registry, so a registered model round-trips unchanged.
"""

from __future__ import annotations

from ..calibration.drift import BiasDrift, parse_drift
from ..exceptions import FtkinError, InvalidInput
from .json_reader import JsonReader, NestedReader


def drift_to_document(drift: BiasDrift | None) -> dict | None:
    """The ``drift`` entry of a calibration file (None without a trajectory)."""
    if drift is None:
        return None
    return {
        "model": drift.model,
        "selected_by": drift.selected_by,
        "times": drift.times,
        "bias": drift.bias,
        "bias_std": drift.bias_std,
        **drift.kind.to_document(drift),
        "time_scale": drift.time_scale,
        "criteria": {name: float(value) for name, value in drift.criteria.items()},
        "recorded_span": drift.recorded_span,
    }


def drift_from_document(reader: JsonReader) -> BiasDrift | None:
    """The :class:`BiasDrift` of a parsed calibration document (None when absent or null)."""
    data = reader.optional_object("drift")
    if data is None:
        return None
    sub = NestedReader(reader.path, data, "drift")
    try:
        kind = parse_drift(sub.get("model"))
    except InvalidInput as error:
        reader.fail(str(error), "drift.model")
    times = data.get("times")
    count = len(sub.array("times", (len(times) if isinstance(times, list) else 0,)))
    criteria = data.get("criteria") or {}
    if not isinstance(criteria, dict):
        reader.fail("expected an object of numbers", "drift.criteria")
    NestedReader(reader.path, criteria, "drift.criteria").check_types(
        dict.fromkeys(criteria, "number")
    )
    try:
        return BiasDrift(
            model=kind.name,
            selected_by=sub.optional("selected_by", str, "given"),
            times=sub.array("times", (count,)),
            bias=sub.array("bias", (count, 6)),
            bias_std=sub.array("bias_std", (count, 6)),
            time_scale=sub.number("time_scale") if "time_scale" in data else 1.0,
            criteria={str(name): float(value) for name, value in criteria.items()},
            recorded_span=sub.array("recorded_span", (2,), required=False),
            **kind.from_document(sub),
        )
    except (FtkinError, TypeError, ValueError) as error:
        reader.fail(f"malformed: {error}", "drift")
