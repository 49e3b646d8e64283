"""Colours of the drawn vectors and the legend overlaid on a static page.

The arrow colours are saturated and drawn unlit (``MeshBasicMaterial``) so
that they appear on screen exactly as given and nothing else in the scene
(white/grey/orange arm, blue background, thin red/green/blue triads) shares
them; the browser test finds each arrow by its colour.
"""

from __future__ import annotations

import html
from dataclasses import dataclass


@dataclass(frozen=True)
class Layer:
    """One kind of drawn object: scene node name, colour ``0xRRGGBB`` and legend label."""

    name: str
    color: int
    label: str

    @property
    def rgb(self) -> tuple[int, int, int]:
        """The colour as ``(r, g, b)`` in 0–255."""
        return (self.color >> 16) & 0xFF, (self.color >> 8) & 0xFF, self.color & 0xFF

    @property
    def css(self) -> str:
        """The colour as CSS ``#rrggbb``."""
        return f"#{self.color:06x}"


MEASURED = Layer("measured", 0xFF00FF, "measured force − bias, R_BS (F − F0)")
GRAVITY = Layer("gravity", 0x00FFFF, "predicted tool gravity, a = R_BS Gs")
CONTACT = Layer("contact", 0xFFFF00, "compensated contact force, R_BS F′")
CENTER_OF_MASS = Layer("center_of_mass", 0x00A050, "tool centre of mass")
BASE_GRAVITY = Layer("base_gravity", 0x8000FF, "gravity direction in the base (estimated tilt)")
VERTICAL = Layer("vertical", 0x404040, "base −z (no tilt)")

ARROWS = (MEASURED, GRAVITY, CONTACT)
"""The force arrows anchored at the sensor origin."""

LAYERS = (MEASURED, GRAVITY, CONTACT, CENTER_OF_MASS, BASE_GRAVITY, VERTICAL)
"""Everything ftkin draws besides the arm and the sensor triad."""


def legend_html(scale_m_per_n: float, tilt_deg: tuple[float, float], exaggeration: float, caption: str = "") -> str:
    """An HTML block (absolute-positioned, top left) listing the colours and the scale."""
    rows = []
    for layer in LAYERS:
        label = layer.label
        if layer is BASE_GRAVITY:
            label += f": U={tilt_deg[0]:+.3f}°, V={tilt_deg[1]:+.3f}°"
            if exaggeration != 1.0:
                label += f" (drawn ×{exaggeration:g})"
        rows.append(
            f'<div><span style="display:inline-block;width:14px;height:14px;margin-right:6px;'
            f'vertical-align:middle;background:{layer.css}"></span>{html.escape(label)}</div>'
        )
    scale_cm = 100.0 * scale_m_per_n
    rows.append(f"<div>scale: 1 N = {scale_cm:.3g} cm (arrows from the sensor origin; triad = sensor frame x,y,z = r,g,b)</div>")
    if caption:
        rows.append(f"<div>{html.escape(caption)}</div>")
    return (
        '<div id="ftkin-legend" style="position:absolute;left:8px;top:8px;padding:6px 8px;'
        "background:rgba(255,255,255,0.85);font:13px sans-serif;color:#111;border-radius:4px;"
        'line-height:18px;z-index:10">' + "".join(rows) + "</div>"
    )


def add_legend(page: str, legend: str) -> str:
    """Insert ``legend`` just before the page's closing ``</body>``."""
    index = page.rfind("</body>")
    if index < 0:
        return page + legend
    return page[:index] + legend + page[index:]
