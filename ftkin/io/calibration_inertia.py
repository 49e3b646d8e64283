"""The ``inertia`` of a dynamic calibration in the calibration file
(:mod:`ftkin.io.calibration_file`).
"""

from __future__ import annotations

import numpy as np

from ..calibration.dynamic import DynamicCalibrationResult
from ..calibration.estimate import CalibrationResult
from ..calibration.log_cholesky import is_physically_consistent, parameters_from_body


def inertia_document(result: CalibrationResult) -> dict:
    """``inertia`` (3×3 about the COM, sensor axes [kg·m²]) of a dynamic calibration, else
    nothing.
    """
    return (
        {}
        if result.inertia_about_com_in_sensor is None
        else {"inertia": result.inertia_about_com_in_sensor}
    )


def with_inertia(reader, result: CalibrationResult, inertia: np.ndarray) -> CalibrationResult:
    """The :class:`~ftkin.calibration.dynamic.DynamicCalibrationResult` of a file with an
    ``inertia``.
    """
    if not np.allclose(
        inertia, inertia.T, rtol=0.0, atol=1e-12 * max(1.0, float(np.abs(inertia).max()))
    ):
        reader.fail("the inertia must be a symmetric 3×3 matrix [kg·m²]", "inertia")
    errors = reader.get("std_errors", required=False)
    inertia_errors = None
    if isinstance(errors, dict) and errors.get("inertia") is not None:
        inertia_errors = reader.array("std_errors.inertia", (3, 3), source=errors["inertia"])
    theta = parameters_from_body(result.tool_mass, result.center_of_mass, inertia)
    if not is_physically_consistent(theta, tolerance=-1e-12):
        reader.fail(
            "the inertia is not physically consistent with the mass and centre of mass (a "
            "principal moment "
            "is negative or violates the triangle inequality)",
            "inertia",
        )
    inertia_fields = {
        "inertia_about_com_in_sensor": inertia,
        "inertia_std_errors": inertia_errors,
        "inertial_parameters": theta,
    }
    return DynamicCalibrationResult(**{**vars(result), **inertia_fields})
