"""Importing ftkin loads no heavy optional dependency; ``ftkin --version`` loads not even numpy."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import ftkin

ROOT = Path(__file__).resolve().parent.parent
HEAVY = ("scipy", "matplotlib", "meshcat", "rosbags", "yourdfpy", "mujoco")


def _modules_after(code: str) -> set[str]:
    environment = {**os.environ, "PYTHONPATH": str(ROOT)}
    out = subprocess.run(
        [sys.executable, "-c", code + "\nimport sys; print(' '.join(sys.modules))"],
        capture_output=True,
        text=True,
        env=environment,
        check=True,
        cwd=ROOT,
    ).stdout
    return set(out.split())


def test_import_and_every_public_name_skip_the_heavy_dependencies():
    loaded = _modules_after("import ftkin\nfrom ftkin import *")
    assert "pinocchio" in loaded and not [name for name in HEAVY if name in loaded]


def test_version_answers_without_the_library():
    code = "from ftkin.cli import main\nassert main(['--version']) == 0"
    loaded = _modules_after(code)
    assert "numpy" not in loaded and "pinocchio" not in loaded and "ftkin.control" not in loaded


def test_lazy_names_are_the_modules_objects():
    from ftkin.control.compensation import Compensator

    assert ftkin.Compensator is Compensator
    assert "Compensator" in dir(ftkin)
