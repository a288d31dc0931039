"""The one check that an input to the optimizer is a quad(-dominant) mesh, not a triangle mesh.

A triangle is always planar, so "PQ" holds trivially, and a vertex where six
triangles meet has no cone through its face planes: the optimizer has nothing
to do (``pq`` "converges" at once) or cannot succeed (``conical``), and the CAD
stage fails later.  ``fabricate optimize`` and the input stage of ``fabricate
run`` (when the mesh is optimized as it is, without subdivision) call
:func:`require_quads` first and point to the remesher.
"""
from __future__ import annotations

import numpy as np

from optimize.errors import MeshError
from optimize.mesh import Mesh

MAX_TRIANGLE_SHARE = 0.5
"""A mesh with more than this share of triangles is a triangle mesh (remeshed quad meshes keep a
few 3-gons at umbilics)."""


def triangle_share(mesh: Mesh) -> tuple[int, float]:
    """(number of triangles, their share of the faces)."""
    n = int(np.count_nonzero(mesh.face_sizes == 3))
    return n, n / max(mesh.n_faces, 1)


def require_quads(mesh: Mesh, source: str, *, hint: str) -> None:
    """Raise :class:`MeshError` when ``mesh`` is a triangle mesh (``hint``: where to go instead)."""
    n, share = triangle_share(mesh)
    if share <= MAX_TRIANGLE_SHARE:
        return
    raise MeshError(f"{source}: {n} of {mesh.n_faces} faces are triangles, expected a quad(-dominant) "
                    f"mesh: triangles are always planar and have no cone, so there is nothing to "
                    f"optimize into panels; {hint}")


CLI_HINT = ("turn the surface into quads first: `fabricate remesh SURFACE --edge-length L -o quads.obj` "
            "(L in --units) (or give it to `fabricate run` as input.surface)")
RUN_HINT = ("give the triangle surface as input.surface (with input.edge_length) to remesh it into "
            "quads, or as input.control with subdivision levels; `fabricate remesh` does the same "
            "on its own")
