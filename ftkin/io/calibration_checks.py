"""Consistency checks of a calibration document, beyond types and shapes.

JSON parsing refuses duplicate keys (which value is meant would be
ambiguous) and absurd nesting; the parameters must agree with the derived
fields written beside them (``tool_weight``, ``tool_mass``, ``base_tilt_deg``);
a covariance must be symmetric positive semi-definite; the units a file
states must be ftkin's; the parameters must be physically plausible (centre of
mass within 10 m of the sensor, bias and weight at most 1e6 N or N·m,
g between 1 and 30 m/s²). Booleans are not numbers. Each failure is a
:class:`~ftkin.exceptions.CalibrationFileError`
naming the key.
"""

from __future__ import annotations

import json
import math

import numpy as np

from ..calibration.model import GRAVITY_RANGE
from ..exceptions import CalibrationFileError
from ..validation import MAX_WRENCH


def short_repr(value) -> str:
    """``repr`` cut to 80 characters for messages."""
    text = repr(value)
    return text if len(text) <= 80 else text[:80] + "..."


def _refuse_duplicate_keys(pairs):
    document = {}
    for key, value in pairs:
        if key in document:
            raise _DuplicateKey(key)
        document[key] = value
    return document


class _DuplicateKey(ValueError):
    pass


def parse_calibration_json(text: str, path: str) -> dict:
    """Parse the JSON of a calibration file: duplicate keys, NaN/Infinity and absurd nesting
    refused.
    """
    try:
        return json.loads(text, object_pairs_hook=_refuse_duplicate_keys)
    except _DuplicateKey as error:
        raise CalibrationFileError(
            path, "duplicate key in a JSON object: which value is meant is ambiguous", str(error)
        ) from None
    except json.JSONDecodeError as error:
        raise CalibrationFileError(
            path,
            f"not valid JSON (truncated or corrupt?) at line {error.lineno}, column {error.colno}: "
            f"{error.msg}",
        ) from None
    except RecursionError:
        raise CalibrationFileError(
            path, "JSON nested too deeply; expected an ftkin calibration document"
        ) from None
    except ValueError as error:  # a number with too many digits
        raise CalibrationFileError(path, f"not a valid calibration document: {error}") from None


def check_document(reader, document: dict, result, units: dict) -> None:
    """Every check of a parsed calibration: derived fields, units, plausibility, covariance."""
    check_derived(reader, document, result)
    check_units(reader, document, units)
    check_plausible(reader, result)
    check_covariance(reader, result.covariance)


def check_derived(reader, document: dict, result) -> None:
    """Refuse a derived field (``tool_weight``, ``tool_mass``, ``base_tilt_deg``) that disagrees
    with the parameters.
    """
    derived = (
        ("tool_weight", result.tool_weight, "N", "|gravity_in_base|"),
        ("tool_mass", result.tool_mass, "kg", "|gravity_in_base| / g"),
    )
    for key, value, unit, source in derived:
        if key in document:
            stated = reader.number(key)
            if not math.isclose(stated, value, rel_tol=1e-9, abs_tol=1e-12):
                reader.fail(
                    f"{stated} {unit} disagrees with {source} = {value} {unit} (file edited by "
                    "hand?)",
                    key,
                )
    if "base_tilt_deg" in document:
        stated = reader.array("base_tilt_deg", (2,))
        expected = np.array(result.base_tilt_deg)
        if not np.allclose(stated, expected, rtol=1e-9, atol=1e-9):
            reader.fail(
                f"{stated.tolist()} deg disagrees with the tilt of gravity_in_base = "
                f"{expected.tolist()} deg "
                "(file edited by hand?)",
                "base_tilt_deg",
            )


def check_covariance(reader, covariance) -> None:
    """Refuse a covariance that is not symmetric positive semi-definite."""
    if covariance is None:
        return
    scale = max(float(np.max(np.abs(covariance))), 1e-300)
    asymmetry = float(np.max(np.abs(covariance - covariance.T)))
    if asymmetry > 1e-9 * scale:
        reader.fail(
            f"not symmetric (largest |C - C^T| = {asymmetry:.3g}); expected a covariance matrix",
            "covariance",
        )
    smallest = float(np.linalg.eigvalsh(0.5 * (covariance + covariance.T))[0])
    if smallest < -1e-9 * scale:
        reader.fail(
            f"not positive semi-definite (eigenvalue {smallest:.3g}); expected a covariance matrix",
            "covariance",
        )


MAX_COM_DISTANCE = 10.0
"""Farthest plausible centre of mass from the sensor [m] (the planner's bound too)."""
MAX_LOAD = MAX_WRENCH
"""Largest plausible bias or tool weight [N, N·m]: the samples reader's bound on a reading."""


def check_units(reader, document: dict, units: dict) -> None:
    """Refuse a file whose ``units`` name another unit than ftkin's for a key (e.g.
    ``"force_offset": "kN"``).
    """
    stated = reader.optional_object("units")
    if stated is None:
        return
    for key, expected in units.items():
        if key in stated and key in document:
            value = stated[key]
            unit, ours = (str(value).split(",")[0].strip(), expected.split(",")[0].strip())
            if not isinstance(value, str) or unit.replace("·", "*") != ours:
                reader.fail(
                    f"{key} is stated in {short_repr(value)}, but ftkin files are in {ours!r} "
                    "(convert the values, or the file is not ftkin's)",
                    "units",
                )


def check_plausible(reader, result) -> None:
    """Refuse parameters no tool on a wrist sensor has: a wrong unit or a corrupt file that still
    parses.
    """
    distance = float(np.linalg.norm(result.center_of_mass))
    if distance > MAX_COM_DISTANCE:
        reader.fail(
            f"the centre of mass is {distance:.4g} m from the sensor; expected at most "
            f"{MAX_COM_DISTANCE:g} m "
            "(millimetres written as metres?)",
            "center_of_mass",
        )
    for key, value in (
        ("force_offset", result.force_offset),
        ("torque_offset", result.torque_offset),
        ("gravity_in_base", result.gravity_in_base),
    ):
        if float(np.max(np.abs(value))) > MAX_LOAD:
            reader.fail(
                f"{np.asarray(value).tolist()} is beyond ±{MAX_LOAD:g} (N or N·m): not a load", key
            )
    if not GRAVITY_RANGE[0] <= result.g <= GRAVITY_RANGE[1]:
        reader.fail(
            f"g = {result.g:g} m/s² is outside {GRAVITY_RANGE[0]:g}..{GRAVITY_RANGE[1]:g} (Earth: "
            "9.80665)",
            "g",
        )
