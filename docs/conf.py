"""Sphinx configuration for the ftkin documentation (``make docs``).

Build: ``.venv/bin/sphinx-build -W --keep-going -q -b html docs docs/_build/html``.
Pages are Markdown (MyST); the API reference is generated from the Google-style
docstrings in the code (docs/api/*.md are written by api_pages.py).
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))  # build from a checkout even without `pip install -e .`

from ftkin._version import __version__  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
import api_pages  # noqa: E402

# docs/api/*.md follow the package layout: regenerated (when changed) at every build.
api_pages.write_pages(Path(__file__).resolve().parent)

project = "ftkin"
author = "ftkin contributors"
copyright = "ftkin contributors"  # noqa: A001 (Sphinx's name)
version = __version__
release = __version__

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",
    "sphinx.ext.viewcode",
    "sphinx.ext.mathjax",
    "myst_parser",
]

source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
root_doc = "index"
exclude_patterns = ["_build", "Thumbs.db", ".DS_Store"]

html_theme = "furo"
html_title = f"ftkin {release}"

# MyST: Markdown pages; "## Heading" gets an anchor usable as page.md#heading.
myst_heading_anchors = 3
myst_enable_extensions = ["dollarmath"]

# Autodoc: the code is the truth. Optional extras are imported lazily by ftkin;
# mock only the ones missing here so the build never needs them installed.
_OPTIONAL = ["meshcat", "rosbags", "matplotlib", "mujoco", "yourdfpy"]
autodoc_mock_imports = [name for name in _OPTIONAL if importlib.util.find_spec(name) is None]
autodoc_member_order = "bysource"
autodoc_typehints = "description"
autodoc_default_options = {"show-inheritance": True}

# Napoleon: Google-style docstrings. "Attributes:" sections become :ivar: fields,
# not attribute directives, so dataclass fields documented both in the class
# docstring and by :members: are not duplicate object descriptions.
napoleon_google_docstring = True
napoleon_numpy_docstring = False
napoleon_use_ivar = True
napoleon_use_rtype = False
