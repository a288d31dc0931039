"""Lazy re-exports for package ``__init__`` files (PEP 562).

A package lists ``name -> submodule``; a name is imported on first access,
so importing one light submodule (``optimize.errors``) does not load the
solvers, SciPy or a CAD kernel.  Submodules stay importable as attributes;
a re-exported name must not be the name of a submodule (once that submodule
is imported, the package attribute is the module).
"""
from __future__ import annotations

import importlib
from typing import Callable


def lazy_exports(package: str, exports: dict[str, str], namespace: dict) -> tuple[Callable, Callable]:
    """``(__getattr__, __dir__)`` for ``package`` re-exporting ``exports``.

    exports : name -> ``".module"`` (the same name there) or ``".module:other"``.

    ``namespace`` is the package's ``globals()``: a loaded name is stored there, so
    the second access costs nothing.
    """
    def __getattr__(name: str):
        module = exports.get(name)
        if module is None:
            try:  # a submodule asked for as an attribute
                return importlib.import_module(f"{package}.{name}")
            except ModuleNotFoundError as exc:
                if exc.name != f"{package}.{name}":
                    raise
                raise AttributeError(f"module {package!r} has no attribute {name!r}") from None
        module, _, attr = module.partition(":")
        value = getattr(importlib.import_module(module, package), attr or name)
        namespace[name] = value
        return value

    def __dir__() -> list[str]:
        return sorted(set(namespace) | set(exports))

    return __getattr__, __dir__
