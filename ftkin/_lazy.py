"""Public names that load their module on first access (PEP 562), for ``ftkin`` and its stages.

A package lists ``{name: relative module}`` and gets the module-level
``__getattr__`` and ``__dir__`` that import the defining module only when a
name is first used, so ``import ftkin`` (and the CLI's start) stay light.
"""

import importlib


def lazy_exports(package: str, exports: dict[str, str], namespace: dict):
    """``(__getattr__, __dir__)`` for the package ``package`` whose globals are ``namespace``."""

    def __getattr__(name: str):
        module = exports.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = namespace[name] = getattr(importlib.import_module(module, package), name)
        return value

    def __dir__() -> list[str]:
        return sorted(set(namespace) | set(namespace.get("__all__", ())))

    return __getattr__, __dir__
