"""glTF 2.0 (GLB) with one node per part, named by its id: for web viewers and coordination platforms.

``model.glb`` of the report merges the parts of each kind into one mesh (a
light scene for the 3D view of report.html); ``parts.glb`` here keeps every
part as its own node and mesh (``P0001``, ``B0001``, ``N0001``: the ids of the
STEP file and the bill of materials), coloured by kind.  Units and axes are
glTF's own: metres, y up (the model's millimetres times 0.001, z up turned to
y up), as every glTF viewer expects; the scale is stated in ``asset.extras``.
"""
from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from optimize.errors import ExportError, write_error

from ..cad.parts import COLOURS


def _triangles(faces) -> np.ndarray:
    """(t, 3) fan triangles of the convex polygons ``faces`` (vertex-index tuples)."""
    return np.array([(f[0], f[j], f[j + 1]) for f in faces for j in range(1, len(f) - 1)], dtype=np.int64)


def write_parts_gltf(parts, path) -> dict:
    """Write ``parts.glb`` (atomic): one node per part.  Returns facts: ``file, bytes, nodes, seconds``."""
    from fabricate.report.glb import GlbMesh, write_glb

    t0 = time.perf_counter()
    path = Path(path)
    meshes = []
    for g in parts.groups:
        tri = _triangles(g.faces)
        colour = (*COLOURS[g.kind], 0.6 if g.kind == "panel" else 1.0)
        for i, pid in enumerate(g.ids):
            meshes.append(GlbMesh(name=pid, positions=g.vertices[i], indices=tri, color=colour,
                                  metallic=0.0 if g.kind == "panel" else 0.6, roughness=0.4))
    if not meshes:
        raise ExportError(f"{path}: no parts to write")
    try:
        facts = write_glb(path, meshes, generator="conical-fab parts (metres, y up; model mm x 0.001)")
    except OSError as exc:
        raise write_error(path, "glTF file", exc) from exc
    return dict(facts or {}, file=path.name, bytes=path.stat().st_size, nodes=len(meshes), units="m",
                seconds=time.perf_counter() - t0)
