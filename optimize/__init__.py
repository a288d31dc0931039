"""Geometry core: polygon meshes, measures and the optimizers of conical meshes."""
from .api import optimize_mesh
from .errors import ConfigError, ConvergenceError, ExportError, MeshError
from .mesh import Mesh
from .result import OptimizeResult
from .tolerances import Tolerances

__all__ = ["ConfigError", "ConvergenceError", "ExportError", "Mesh", "MeshError", "OptimizeResult",
           "Tolerances", "optimize_mesh"]
