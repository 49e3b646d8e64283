"""Readable text summaries of a calibration (what the CLI prints)."""

from __future__ import annotations

import numpy as np

from .model import WRENCH_CHANNELS


def _decimals(errors, decimals: int) -> int:
    """Enough decimals to show two significant digits of the smallest standard error."""
    errors = np.atleast_1d(np.asarray(errors, dtype=float)) if errors is not None else np.zeros(0)
    positive = errors[np.isfinite(errors) & (errors > 0)]
    if positive.size == 0:
        return decimals
    return int(min(max(decimals, np.ceil(-np.log10(positive.min())) + 1), 9))


def _vector(values, decimals: int, errors=None) -> str:
    decimals = _decimals(errors, decimals)
    text = "[" + ", ".join(f"{value:+.{decimals}f}" for value in values) + "]"
    if errors is not None:
        text += " ± [" + ", ".join(f"{value:.{decimals}f}" for value in errors) + "]"
    return text


def _scalar(value, decimals: int, error=None) -> str:
    decimals = _decimals(error, decimals)
    return f"{value:.{decimals}f}" + (f" ± {error:.{decimals}f}" if error is not None else "")


def format_summary(result) -> str:
    """Text of a :class:`~ftkin.calibration.CalibrationResult`: parameters with units (± standard
    error), fit and provenance.
    """
    errors = result.std_errors or {}
    tilt_u, tilt_v = result.base_tilt_deg
    tilt_errors = np.rad2deg(errors["base_tilt"]) if "base_tilt" in errors else (None, None)
    lines = [
        f"ftkin calibration: method {result.method}, {result.pose_count} poses, "
        f"{result.sample_count} readings",
        f"  force_offset    F0 = {_vector(result.force_offset, 4, errors.get('force_offset'))} N "
        "(sensor frame)",
        f"  torque_offset   M0 = {_vector(result.torque_offset, 4, errors.get('torque_offset'))} "
        "N·m (sensor frame)",
        f"  center_of_mass  P  = {_vector(result.center_of_mass, 4, errors.get('center_of_mass'))} "
        "m (sensor frame)",
        "  gravity_in_base a  = "
        f"{_vector(result.gravity_in_base, 4, errors.get('gravity_in_base'))} N (base frame)",
        f"  tool_weight     G  = {_scalar(result.tool_weight, 3, errors.get('tool_weight'))} N",
        f"  tool_mass       m  = {_scalar(result.tool_mass, 4, errors.get('tool_mass'))} kg (g = "
        f"{result.g:g} m/s²)",
        f"  base_tilt       U  = {_scalar(tilt_u, 3, tilt_errors[0])}°, V = "
        f"{_scalar(tilt_v, 3, tilt_errors[1])}°",
    ]
    lines.extend(_mount_lines(result) + _inertia_lines(result))
    if result.drift is not None:
        lines.append(f"  bias drift: {result.drift.describe()}")
        if result.drift.model != "none":
            lines.append(
                "    F0, M0 above are the bias at the end of the recording (t = "
                f"{result.drift.end_time:.6g} s)"
            )
        if result.drift.criteria:
            lines.append(
                "    BIC: "
                + ", ".join(f"{name} {value:.1f}" for name, value in result.drift.criteria.items())
            )
    if result.pose_count:
        rms = result.residual_rms
        lines.append(
            "  residual RMS per pose: "
            + ", ".join(f"{name} {value:.4f}" for name, value in zip(WRENCH_CHANNELS, rms))
            + " (N, N·m)"
        )
        relative = 100.0 * result.mean_relative_error
        lines.append(
            "  mean relative compensation error: "
            + ", ".join(f"{name} {value:.2f}%" for name, value in zip(WRENCH_CHANNELS, relative))
        )
    if result.diagnostics is not None:
        lines.extend(_diagnostics_lines(result.diagnostics))
    if result.urdf:
        lines.append(f"  kinematics: {result.urdf} (sensor frame {result.sensor_frame})")
    return "\n".join(lines)


def _inertia_lines(result) -> list[str]:
    """The identified inertia (± standard errors) and its principal moments, if any."""
    if not result.has_inertia:
        return []
    inertia = result.inertia_about_com_in_sensor
    errors = result.inertia_std_errors
    errors = np.full((3, 3), np.nan) if errors is None else errors
    lines = ["  inertia_about_com_in_sensor [kg·m²] (± standard error):"]
    for row, error in zip(inertia, errors):
        lines.append("    [" + ", ".join(f"{v:+.6f} ± {e:.6f}" for v, e in zip(row, error)) + "]")
    moments = np.linalg.eigvalsh(inertia)
    lines.append("  principal moments: " + ", ".join(f"{m:.6f}" for m in moments) + " kg·m²")
    return lines


def _mount_lines(result) -> list[str]:
    """The estimated mount and a non-default reading convention, if any."""
    lines = []
    if result.mount_mode != "none":
        errors = ", ".join(f"{name} ± {value:.3f}°" for name, value in result.mount_std_deg.items())
        lines.append(
            f"  mount_rpy_deg   R_M = {_vector(result.mount_rpy_deg, 3)}° (roll, pitch, yaw; URDF "
            "sensor frame → "
            f"real sensor frame, estimated: {result.mount_mode}; {errors})"
        )
    if result.sensor_sign != 1 or result.flip_axis is not None:
        flip = f", {result.flip_axis} axis reversed" if result.flip_axis else ""
        lines.append(
            f"  readings: sensor_sign {result.sensor_sign:+d}{flip} (applied to every reading)"
        )
    return lines


_NOISE_SOURCE_TEXT = {
    "given": "given",
    "spread": "from the spread of repeated readings",
    "residuals": "from the residuals",
}


def _diagnostics_lines(diagnostics) -> list[str]:
    """Noise, goodness of fit, outliers, observability and warnings of an ml fit."""
    noise = diagnostics.noise
    lines = [
        "  noise per reading "
        f"({_NOISE_SOURCE_TEXT.get(diagnostics.noise_source, diagnostics.noise_source)}): "
        f"force {_vector(noise.force_std, 4).replace('+', '')} N, torque "
        f"{_vector(noise.torque_std, 5).replace('+', '')} N·m"
        + (f"; loss {diagnostics.loss}" if diagnostics.loss != "linear" else "")
    ]
    if diagnostics.noise_source == "residuals":
        fit = "not testable (noise estimated from the same residuals)"
    elif diagnostics.fit_ok:
        fit = "consistent with the noise"
    else:
        fit = (
            "DOES NOT FIT the noise; standard errors scaled by "
            f"{diagnostics.covariance_scale**0.5:.2f}"
        )
    p_text = f", p = {diagnostics.p_value:.2g}" if np.isfinite(diagnostics.p_value) else ""
    lines.append(
        f"  goodness of fit: chi-square {diagnostics.chi_square:.1f} for {diagnostics.dof} "
        f"dof{p_text}: {fit}"
    )
    lines.append(
        "  reduced chi-square per channel: "
        + ", ".join(
            f"{name} {value:.2f}"
            for name, value in zip(WRENCH_CHANNELS, diagnostics.channel_chi_square)
        )
    )
    worst = (
        int(np.nanargmax(diagnostics.pose_normalized_residuals))
        if len(diagnostics.pose_ids)
        else None
    )
    if worst is not None and np.isfinite(diagnostics.pose_normalized_residuals[worst]):
        lines.append(
            f"  largest pose residual: pose {diagnostics.pose_ids[worst]} "
            f"{diagnostics.pose_normalized_residuals[worst]:.2f}σ (p = "
            f"{diagnostics.pose_p_values[worst]:.2g})"
        )
    if diagnostics.outlier_pose_ids:
        lines.append("  OUTLIER poses: " + ", ".join(str(i) for i in diagnostics.outlier_pose_ids))
    if diagnostics.dropped_pose_ids:
        lines.append(
            "  dropped as outliers before the final fit: poses "
            + ", ".join(str(i) for i in diagnostics.dropped_pose_ids)
        )
    weakest = ", ".join(f"{weight:+.2f} {name}" for name, weight in diagnostics.weakest_components)
    lines.append(
        f"  observability: condition number {diagnostics.condition_number:.3g}, weakest direction "
        f"{weakest}"
    )
    lines.extend(f"  WARNING: {message}" for message in diagnostics.warnings)
    return lines
