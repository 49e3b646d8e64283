"""Public names that load their module on first access (PEP 562), for ``ftkin`` and its stages.

A package lists ``{name: relative module}`` and gets the module-level
``__getattr__`` and ``__dir__`` that import the defining module only when a
name is first used, so ``import ftkin`` (and the CLI's start) stay light.

``moved`` lists names that left the package for another (``{name: relative package}``): they
still resolve, with a ``FutureWarning`` that names where to import them from, for one release.
"""

import importlib
import warnings


def lazy_exports(
    package: str, exports: dict[str, str], namespace: dict, moved=None, subpackages=()
):
    """``(__getattr__, __dir__)`` for the package ``package`` whose globals are ``namespace``;
    ``subpackages`` (names) import on first access too (``ftkin.control`` after ``import ftkin``).
    """
    moved = dict(moved or {})
    subpackages = frozenset(subpackages)

    def __getattr__(name: str):
        module = exports.get(name)
        if module is None and name in subpackages:
            value = namespace[name] = importlib.import_module(f".{name}", package)
            return value
        if module is None:
            if name in moved:
                home = importlib.import_module(moved[name], package)
                warnings.warn(
                    f"{package}.{name} is no longer exported by {package}: import it from "
                    f"{home.__name__} (from {home.__name__} import {name}); the old import "
                    "works for this release only",
                    FutureWarning,
                    stacklevel=2,
                )
                return getattr(home, name)
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = namespace[name] = getattr(importlib.import_module(module, package), name)
        return value

    def __dir__() -> list[str]:
        return sorted(set(namespace) | set(namespace.get("__all__", ())))

    return __getattr__, __dir__
