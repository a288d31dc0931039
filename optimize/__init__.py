"""Geometry core: polygon meshes, measures and the optimizers of conical meshes.

Subpackages: ``mesh`` (model, topology, measures, files), ``terms`` (unknowns and the
problem's terms), ``solvers`` (default and the paper's methods), ``linalg`` (sparse
factorizations), ``proximity`` (closest points), ``modelling`` (shapes, designs,
subdivision, strips), ``remesh`` (principal-direction remeshing); ``api`` and ``options``
are the entry point and its settings.

Names are loaded on first use (PEP 562): ``import optimize.errors`` or
``fabricate --help`` does not pay for SciPy and the solvers, and
``from optimize import optimize_mesh`` works as before.
"""
from ._lazy import lazy_exports

_EXPORTS = {
    "optimize_mesh": ".api",
    "ConfigError": ".errors", "ConvergenceError": ".errors", "ExportError": ".errors", "MeshError": ".errors",
    "Mesh": ".mesh", "measures": ".mesh:measures",  # (the README's example imports measures from here)
    "OptimizeResult": ".result",
    "Tolerances": ".tolerances",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS, globals())
