"""``python -m ftkin.cli``: the same as the ``ftkin`` command."""

from . import entry_point

entry_point()
