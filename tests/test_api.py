"""The public API: every exported name exists, the list is sorted, a version is set."""

from __future__ import annotations

import importlib
import importlib.util
import re
from pathlib import Path

import pytest

import ftkin


def test_every_name_in_all_exists():
    missing = [name for name in ftkin.__all__ if not hasattr(ftkin, name)]
    assert missing == []


def test_all_is_sorted_and_unique():
    assert list(ftkin.__all__) == sorted(ftkin.__all__)
    assert len(set(ftkin.__all__)) == len(ftkin.__all__)


def test_version_is_a_release_string():
    assert isinstance(ftkin.__version__, str)
    assert re.fullmatch(r"\d+\.\d+\.\d+([.-]?\w+)?", ftkin.__version__)


def test_exceptions_derive_from_the_root():
    for name in (
        "CalibrationFileError",
        "FrameNotFound",
        "InvalidInput",
        "InvalidSamples",
        "MissingDependency",
        "UnobservableParameters",
        "UrdfError",
    ):
        assert issubclass(getattr(ftkin, name), ftkin.FtkinError), name


STAGES = ("kinematics", "calibration", "control", "planning", "io", "sim", "viz", "sensors")


def test_a_stages_name_is_not_at_the_top_level():
    """ftkin was never released: a stage's name outside the top level's ``__all__`` is not an
    attribute of ``ftkin`` (an AttributeError, no FutureWarning and no forwarding), and it imports
    from its stage."""
    import warnings

    stages = sorted({*STAGES, *ftkin.STAGES})
    seen = 0
    for stage in stages:
        package = importlib.import_module(f"ftkin.{stage}")
        for name in sorted(set(package.__all__) - set(ftkin.__all__) - set(stages)):
            if importlib.util.find_spec(f"ftkin.{name}") is not None:
                continue  # a module's name: ftkin.<module> is not a public name of the top level
            with warnings.catch_warnings():
                warnings.simplefilter("error")
                with pytest.raises(AttributeError, match=f"has no attribute '{name}'"):
                    getattr(ftkin, name)
                assert getattr(package, name) is not None, f"ftkin.{stage}.{name}"
            seen += 1
    assert seen > 100  # the stages' names were walked (128 on 2026-12-03)


def test_the_top_level_is_the_main_path_in_the_users_order():
    """At most 40 names, grouped as a user meets them, each on the API page docs/api.md."""
    assert len(ftkin.__all__) <= 40
    assert list(ftkin._EXPORTS) == [name for group in ftkin._GROUPS.values() for name in group]
    assert sorted(ftkin._EXPORTS) == ftkin.__all__  # derived, not written twice
    page = (Path(__file__).resolve().parents[1] / "docs" / "api.md").read_text()
    listed = set(re.findall(r"^\| `(?:ftkin\.)?(\w+)`", page, re.M))
    assert sorted(set(ftkin.__all__) - listed) == []  # every exported name on the page
    assert sorted(listed - set(ftkin.__all__)) == []  # and nothing else as a top-level row
    headings = re.findall(r"^## (.+)$", page, re.M)
    assert headings[: len(ftkin._GROUPS)] == list(ftkin._GROUPS)


@pytest.mark.parametrize("stage", STAGES)
def test_every_stage_exports_what_its_all_names(stage):
    package = importlib.import_module(f"ftkin.{stage}")
    assert package.__doc__ and "Depends" in package.__doc__, (
        f"ftkin.{stage} must say what it takes, gives and depends on"
    )
    assert [name for name in package.__all__ if not hasattr(package, name)] == []
    assert len(set(package.__all__)) == len(package.__all__)


@pytest.mark.parametrize("stage", STAGES)
def test_the_top_level_re_exports_the_same_objects(stage):
    package = importlib.import_module(f"ftkin.{stage}")
    for name in package.__all__:
        if name in ftkin.__all__:
            assert getattr(ftkin, name) is getattr(package, name), name


def test_the_top_level_stays_small():
    # Modules are cut by concept, not by a line cap (the 300-line cap is retired). The top level
    # holds only the bottom layer every stage shares: the package, lazy exports, the version, the
    # exceptions, validation, progress bars and option declarations.
    root = Path(ftkin.__file__).parent
    assert sorted(path.name for path in root.glob("*.py")) == [
        "__init__.py",
        "_lazy.py",
        "_version.py",
        "exceptions.py",
        "options.py",
        "progress.py",
        "validation.py",
    ]
