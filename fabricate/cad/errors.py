"""The CAD stage's own input error: a part that cannot be built from this mesh with these settings."""
from __future__ import annotations

from optimize.errors import MeshError


class PartError(MeshError):
    """A panel, beam or node that cannot be built (folded, collapsed, not finite, no volume): bad input,
    exit 2, at a place of the mesh.

    part : the part id (``P0003``); element : the mesh element it is built on (face for a panel, edge
    for a beam, vertex for a node), or None.  The message names both and the setting to change.
    """

    def __init__(self, message: str, part: str | None = None, element: int | None = None):
        super().__init__(message)
        self.part = part
        self.element = element
