"""No two library modules share a file name (the CLI's one module per subcommand excepted)."""

from __future__ import annotations

import collections
from pathlib import Path

import ftkin

PACKAGE = Path(ftkin.__file__).parent


def test_no_two_library_modules_share_a_name():
    places = collections.defaultdict(list)
    for path in PACKAGE.rglob("*.py"):
        relative = path.relative_to(PACKAGE)
        if relative.parts[0] == "cli" or path.name == "__init__.py":
            continue
        places[path.name].append(str(relative))
    shared = {name: sorted(paths) for name, paths in places.items() if len(paths) > 1}
    assert shared == {}, f"rename one side of each: {shared}"
