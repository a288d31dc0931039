"""The exception hierarchy of the package.

Every error carries the facts: which file, line or key, the value found and
what was expected.  The CLI turns each into one line and an exit code.
"""
from __future__ import annotations


class ConicalFabError(Exception):
    """Base class of every error raised on purpose by this package."""

    exit_code = 1


class MeshError(ConicalFabError, ValueError):
    """A mesh file or mesh array that cannot be used (bad input: exit 2)."""

    exit_code = 2


class ConfigError(ConicalFabError, ValueError):
    """A configuration file or value that is not valid (bad input: exit 2)."""

    exit_code = 2


class ConvergenceError(ConicalFabError, RuntimeError):
    """An optimization that did not reach its tolerance (exit 3)."""

    exit_code = 3


class ExportError(ConicalFabError, RuntimeError):
    """A file could not be built or written (exit 4)."""

    exit_code = 4
