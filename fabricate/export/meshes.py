"""Triangle meshes of the parts (fan triangles of the same planar convex polygons) and
their validation with manifold3d.

STL and 3MF carry exactly these triangles.  Every part of a group has the same
triangles over its own vertices, so manifold3d builds one part of each group
(double precision, ``Mesh64``): it must report status ``NoError`` and the
genus of the group's solids (0, a hub tube 1), which depend on the triangles
alone; every vertex of every part must be finite (the one thing about a vertex
that manifold3d's status tells), and the volume of every part's triangles
(:func:`fabricate.cad.geometry.volumes`, of the same fan triangles) is summed against the analytic
volume.  Coordinates are taken relative to ``Parts.local_origin()`` (zero unless the model is far from the origin),
because STL stores float32.  The check is made once per parts object and origin
(:data:`_CHECKED`): the STL and the 3MF writer check the same triangles.
"""
from __future__ import annotations

import weakref

import numpy as np

from optimize.errors import ExportError

from ..cad.geometry import fan_triangles, volumes
from ..cad.parts import GENUS


def group_triangles(group, origin: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``X (p, nv, 3)`` vertices relative to ``origin`` and ``T (t, 3)`` local triangles (outward)."""
    return group.vertices - origin[None, None, :], fan_triangles(group.faces)


def manifold_of(X: np.ndarray, T: np.ndarray):
    """One ``manifold3d.Manifold`` of ``p`` disjoint solids ``X (p, nv, 3)`` sharing triangles ``T``."""
    import manifold3d

    p, nv, _ = X.shape
    tri = (T[None, :, :] + (np.arange(p) * nv)[:, None, None]).reshape(-1, 3)
    mesh = manifold3d.Mesh64(vert_properties=np.ascontiguousarray(X.reshape(-1, 3), dtype=np.float64),
                             tri_verts=np.ascontiguousarray(tri, dtype=np.uint64))
    return manifold3d.Manifold(mesh)


_CHECKED: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
"""``{parts: {origin bytes: facts}}``: the manifold3d checks passed by each (immutable) parts object, while it lives."""


def validate_manifold(parts, origin: np.ndarray | None = None) -> dict:
    """Check every group with manifold3d (once per parts object and origin); return facts (a copy);
    raise ExportError naming a bad part (a failed check is not remembered).

    Each part is one connected closed surface by construction (its faces share
    edges), and every part of a group has the same triangles: manifold3d's status
    and genus of the group's first part are every part's (its vertices finite,
    checked for every part).  Facts: ``status`` ("NoError"), ``components``
    (= parts), ``genus`` of all the solids (1 - parts + their holes),
    ``volume_mm3`` (the triangles' determinants, about each part's first vertex) and ``volume_rel_error`` against
    the analytic sum.
    """
    origin = parts.local_origin() if origin is None else origin
    key = np.asarray(origin, dtype=np.float64).tobytes()
    try:
        known = _CHECKED.setdefault(parts, {})
    except TypeError:  # not weak-referenceable: no cache
        known = {}
    if key not in known:
        known[key] = _validate(parts, origin)
    return dict(known[key])


def require_finite(parts) -> None:
    """ExportError naming the first part with a vertex that is not a finite number (every writer calls it
    before it formats a coordinate: ``nan`` or ``inf`` in a STEP, IFC or 3dm file makes a file that no
    reader takes, or worse, one that reads)."""
    for g in parts.groups:
        finite = np.isfinite(g.vertices).all(axis=(1, 2))
        if not finite.all():
            i = int(np.argmin(finite))
            raise ExportError(f"{g.ids[i]}: a vertex is not a finite number; expected a closed solid of finite points")


def _validate(parts, origin: np.ndarray) -> dict:
    """:func:`validate_manifold` without the cache: manifold3d on the first part of each group (the
    others have its triangles), every vertex finite, the triangles' volumes in numpy."""
    require_finite(parts)    # first: a bad vertex spoils the origin, and so every group after it
    total, analytic, comps, genus = 0.0, 0.0, 0, 0
    for g in parts.groups:
        if not len(g):
            continue
        X, T = group_triangles(g, origin)
        m = manifold_of(X[:1], T)
        status = m.status().name
        if status != "NoError":   # the same triangles in every part: each is rejected, the first named
            raise ExportError(f"{g.ids[0]}: manifold3d rejects the solid ({status}); "
                              "expected a closed oriented 2-manifold")
        holes = GENUS.get(g.member, 0)   # a hub tube has one hole
        if m.genus() != holes:  # each part one closed surface of its genus
            raise ExportError(f"{g.kind} group: manifold3d genus {m.genus()} for {g.ids[0]} (its triangles are every "
                              f"part's), expected {holes} (every part a closed genus-{holes} surface)")
        total += float(volumes(X, g.faces).sum())    # the same fan triangles as T
        analytic += float(g.volume_mm3.sum())
        comps += len(g)
        genus += holes * len(g) - len(g)  # genus of a union of c closed surfaces is 1 - c + their genera
    return {"status": "NoError", "components": comps, "genus": genus + 1, "volume_mm3": total,
            "volume_rel_error": abs(total - analytic) / max(analytic, 1e-300)}
