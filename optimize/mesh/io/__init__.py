"""Mesh files: OBJ, OFF and PLY (ascii and binary), read with errors that name the line."""
from ..._lazy import lazy_exports

_EXPORTS = {
    "FORMATS": ".api", "build_mesh": ".api", "detect_format": ".api", "read_mesh": ".api",
    "write_mesh": ".api",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS, globals())
