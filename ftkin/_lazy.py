"""Public names that load their module on first access (PEP 562), for ``ftkin`` and its stages.

A package lists ``{name: relative module}`` and gets the module-level
``__getattr__`` and ``__dir__`` that import the defining module only when a
name is first used, so ``import ftkin`` (and the CLI's start) stay light.

Every submodule and subpackage of the package resolves on attribute access too
(``ftkin.kinematics.rotations`` after ``import ftkin``, whatever was imported before): the
interpreter sets a submodule as its package's attribute only once something has imported it, so
without this, a module's attribute would depend on import order.
"""

import importlib
import importlib.util


def lazy_exports(package: str, exports: dict[str, str], namespace: dict, subpackages=()):
    """``(__getattr__, __dir__)`` for the package ``package`` whose globals are ``namespace``;
    its submodules and ``subpackages`` (names, listed by ``__dir__``) import on first access
    (``ftkin.control`` after ``import ftkin``, ``ftkin.kinematics.rotations`` after
    ``import ftkin.kinematics``).
    """
    subpackages = frozenset(subpackages)

    def __getattr__(name: str):
        module = exports.get(name)
        if module is None and (name in subpackages or _is_submodule(package, name)):
            value = namespace[name] = importlib.import_module(f".{name}", package)
            return value
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = namespace[name] = getattr(importlib.import_module(module, package), name)
        return value

    def __dir__() -> list[str]:
        return sorted(set(namespace) | set(namespace.get("__all__", ())))

    return __getattr__, __dir__


def _is_submodule(package: str, name: str) -> bool:
    """Whether ``package.name`` is a module or package on disk (dunder names never are: they are
    the interpreter's probes, such as ``__wrapped__``)."""
    if name.startswith("__") or not name.isidentifier():
        return False
    return importlib.util.find_spec(f"{package}.{name}") is not None
