"""Mesh files: OBJ, OFF and PLY (ascii and binary), read with errors that name the line."""
from .api import FORMATS, build_mesh, detect_format, read_mesh, write_mesh

__all__ = ["FORMATS", "build_mesh", "detect_format", "read_mesh", "write_mesh"]
