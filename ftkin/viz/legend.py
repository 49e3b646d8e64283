"""Colours of the drawn vectors and the legend overlaid on a static page.

The arrow colours are saturated and drawn unlit (``MeshBasicMaterial``) so
that they appear on screen exactly as given and nothing else in the scene
(white/grey/orange arm, blue background, thin red/green/blue triads) shares
them; the browser test finds each arrow by its colour.
"""

import html
import re
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


LEGEND_BOX = (0, 0, 268, 190)
"""Screen box the legend never leaves, ``(left, top, right, bottom)`` [px]: top-left corner.

The camera puts the sensor in the middle of the image and keeps the arrows
within half of the half-height around it (:mod:`ftkin.viz.framing`), so at
1024 × 768 the arrows stay out of this corner.
"""


def legend_html(
    scale_m_per_n: float, tilt_deg: tuple[float, float], exaggeration: float, caption: str = ""
) -> str:
    """A small HTML block (top-left corner, inside :data:`LEGEND_BOX`) listing the colours and the
    scale.
    """
    drawn = f" (drawn ×{exaggeration:g})" if exaggeration != 1.0 else ""
    tilt = f": U={tilt_deg[0]:+.3f}°, V={tilt_deg[1]:+.3f}°{drawn}"
    rows = [
        f'<div><span style="display:inline-block;width:10px;height:10px;margin-right:5px;'
        f'vertical-align:middle;background:{layer.css}"></span>'
        f"{html.escape(layer.label + (tilt if layer is BASE_GRAVITY else ''))}</div>"
        for layer in LAYERS
    ]
    rows.append(
        f"<div>1 N = {100.0 * scale_m_per_n:.3g} cm from the sensor origin; "
        "triad x,y,z = r,g,b</div>"
    )
    if caption:
        rows.append(
            '<div style="white-space:nowrap;overflow:hidden;text-overflow:ellipsis">'
            f"{html.escape(caption)}</div>"
        )
    left, top, right, bottom = LEGEND_BOX
    return (
        f'<div id="ftkin-legend" style="position:absolute;left:{left + 6}px;top:{top + 6}px;'
        f"width:{right - left - 22}px;max-height:{bottom - top - 20}px;overflow:hidden;padding:4px "
        "5px;"
        "background:rgba(255,255,255,0.85);font:10px sans-serif;color:#111;border-radius:3px;"
        'line-height:12px;z-index:10">' + "".join(rows) + "</div>"
    )


def add_legend(page: str, legend: str) -> str:
    """Insert ``legend`` just before the page's closing ``</body>``."""
    head, body_end, tail = page.rpartition("</body>")
    return head + legend + body_end + tail if body_end else page + legend


_FETCH = re.compile(
    r'fetch\("data:application/octet-binary;base64,([A-Za-z0-9+/=]*)"\)\s*'
    r"\.then\(res => res\.arrayBuffer\(\)\)\s*"
    r"\.then\(buffer => viewer\.handle_command_bytearray\(new Uint8Array\(buffer\)\)\);"
)
_DECODE = (
    "function ftkinCommand(b){const s=atob(b);const a=new Uint8Array(s.length);"
    "for(let i=0;i<s.length;i++)a[i]=s.charCodeAt(i);viewer.handle_command_bytearray(a);}\n"
)


def inline_commands(page: str) -> str:
    """meshcat's static page with its scene commands run synchronously, in order, before the page's
    load event.

    meshcat 0.3.2 replays each command through ``fetch("data:...")``, a
    promise that may settle after headless Chromium has taken its screenshot
    (an empty scene on a busy machine). Each becomes a direct call that decodes
    the same base64 bytes. A page without such commands is returned unchanged.
    """
    replaced, count = _FETCH.subn(lambda match: f'ftkinCommand("{match.group(1)}");', page)
    head, anchor, tail = replaced.partition("var viewer = new MeshCat.Viewer(")
    return head + _DECODE + anchor + tail if count and anchor else page
