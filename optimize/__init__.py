"""Geometry core: polygon meshes, measures and the optimizers of conical meshes."""
from .errors import ConfigError, ConvergenceError, ExportError, MeshError
from .mesh import Mesh
from .tolerances import Tolerances

__all__ = ["ConfigError", "ConvergenceError", "ExportError", "Mesh", "MeshError", "Tolerances"]
