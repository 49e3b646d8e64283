"""The public API: every exported name exists, the list is sorted, a version is set."""

from __future__ import annotations

import re

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
