"""Write the API reference pages (docs/api/*.md) from the package layout.

Called by conf.py at every build, so a module added to a stage shows up in the
reference without editing the docs; a file is rewritten only when its content
changes. Each stage page has the subpackage's docstring (what the stage takes
and gives), links to its exported names, then every module in full
(``automodule`` with ``:members:``). The flat ``ftkin`` namespace is repeated on
the index page with ``:no-index:``, so each object has one canonical entry: the
module that defines it.
"""

from __future__ import annotations

import importlib
import pkgutil
import re
from pathlib import Path

# Stages in data-path order; inside a stage the listed modules come first (the
# data path inside the stage), then any module added since, alphabetically.
STAGES = [
    ("kinematics", "Kinematics", ["arm", "urdf_loading", "robots", "rotations", "collision"]),
    (
        "calibration",
        "Calibration",
        [
            "samples",
            "model",
            "linear",
            "ml",
            "information",
            "fit_quality",
            "diagnostics",
            "observability",
            "summary",
            "fit_options",
            "estimate",
            "fit_registry",
        ],
    ),
    (
        "control",
        "Control",
        ["compensation", "admittance", "control_frame", "joint_admittance", "sensor_faults"],
    ),
    ("planning", "Planning", ["plan", "design", "constraints", "order", "evaluation"]),
    (
        "io",
        "Input and output",
        [
            "samples_csv",
            "csv_table",
            "bags",
            "static_segments",
            "calibration_file",
            "export",
            "yaml_text",
            "atomic",
        ],
    ),
    ("sim", "Simulation", ["sensor", "placement", "surfaces", "placement_plots", "paper"]),
    (
        "viz",
        "Visualisation",
        ["arrows", "legend", "server", "viewer", "browser", "report"],
    ),
    (
        "sensors",
        "Sensors",
        ["sample", "units", "stream", "ati", "bota", "bota_process", "registry"],
    ),
    (
        "robot",
        "On the robot",
        ["protocols", "franka", "session", "stillness", "samples_log", "loop", "guiding"],
    ),
    ("cli", "Command line", []),
]
BOTTOM = ["exceptions", "validation", "progress"]

# Docstrings that are not valid reStructuredText yet ("|a|" reads as a
# substitution reference): left out of the reference until the code is fixed.
EXCLUDE: dict[str, list[str]] = {}


def automodule(name: str, members: bool = True, no_index: bool = False) -> str:
    """An ``automodule`` directive inside ``eval-rst`` (autodoc emits reStructuredText)."""
    lines = ["```{eval-rst}", f".. automodule:: {name}"]
    if members:
        lines.append("   :members:")
    if no_index:
        lines.append("   :no-index:")
    if name in EXCLUDE:
        lines.append("   :exclude-members: " + ", ".join(EXCLUDE[name]))
    lines.append("```")
    return "\n".join(lines) + "\n"


def stage_modules(package: str, preferred: list[str]) -> list[str]:
    found = sorted(
        m.name
        for m in pkgutil.iter_modules(importlib.import_module(package).__path__)
        if not m.name.startswith("__")
    )
    return [m for m in preferred if m in found] + [m for m in found if m not in preferred]


def defining_module(package: str, modules: list[str], name: str, source_dir: Path) -> str:
    """The module of ``package`` that defines ``name`` (where autodoc documents it)."""
    obj = getattr(importlib.import_module(package), name)
    module = getattr(obj, "__module__", None)
    if isinstance(module, str) and module.startswith(package + "."):
        return module
    for candidate in modules:  # constants have no __module__: find the assignment
        path = source_dir / f"{candidate}.py"
        if path.exists() and re.search(rf"^{re.escape(name)}\b", path.read_text(), re.M):
            return f"{package}.{candidate}"
    return package


def stage_page(package: str, title: str, preferred: list[str], root: Path) -> str:
    full = f"ftkin.{package}"
    modules = stage_modules(full, preferred)
    parts = [f"# `{full}`: {title}\n", automodule(full, members=False)]
    exported = getattr(importlib.import_module(full), "__all__", [])
    if exported:
        source_dir = root / "ftkin" / package
        links = (
            f"{{py:obj}}`~{defining_module(full, modules, name, source_dir)}.{name}`"
            for name in exported
        )
        parts += [
            "Exported from the subpackage (documented in full in its modules below):\n",
            ", ".join(links) + "\n",
        ]
    for module in modules:
        parts += [f"## `{full}.{module}`\n", automodule(f"{full}.{module}")]
    return "\n".join(parts)


def index_page() -> str:
    toctree = "\n".join(package for package, _, _ in STAGES)
    return "\n".join(
        [
            "# API reference\n",
            "Generated from the docstrings (Google style). The flat public API, `ftkin`, comes "
            "first; then one "
            "page per stage of the data path ([Architecture](../architecture.md)), each with the "
            "subpackage's "
            "summary and every module in full.\n",
            f"```{{toctree}}\n:maxdepth: 2\n\n{toctree}\nbottom\n```\n",
            "## `ftkin`: the public API\n",
            "Every name in `ftkin.__all__`. Each is documented where it is defined (the stage "
            "pages); this "
            "section repeats them for reading in one place.\n",
            automodule("ftkin", no_index=True),
        ]
    )


def bottom_page() -> str:
    parts = ["# Bottom layer\n", "Imported by every stage; imports nothing else from ftkin.\n"]
    for module in BOTTOM:
        parts += [f"## `ftkin.{module}`\n", automodule(f"ftkin.{module}")]
    return "\n".join(parts)


def write_pages(docs_dir: Path) -> None:
    """Write docs/api/*.md, touching only the files whose content changed."""
    api = docs_dir / "api"
    api.mkdir(exist_ok=True)
    pages = {"index": index_page(), "bottom": bottom_page()}
    for package, title, preferred in STAGES:
        pages[package] = stage_page(package, title, preferred, docs_dir.parent)
    for name, text in pages.items():
        path = api / f"{name}.md"
        if not path.exists() or path.read_text() != text:
            path.write_text(text)


if __name__ == "__main__":
    write_pages(Path(__file__).resolve().parent)
