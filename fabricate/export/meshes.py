"""Triangle meshes of the parts (fan triangles of the same planar convex polygons) and
their validation with manifold3d.

STL and 3MF carry exactly these triangles.  manifold3d builds every group of
parts (double precision, ``Mesh64``) and must report status ``NoError``,
one component per part, genus 0 each (``genus = 1 - parts`` for the
group), and the analytic volume.  Coordinates are taken relative to
``Parts.local_origin()`` (zero unless the model is far from the origin),
because STL stores float32.  The check is made once per parts object and origin
(:data:`_CHECKED`): the STL and the 3MF writer check the same triangles.
"""
from __future__ import annotations

import weakref

import numpy as np

from optimize.errors import ExportError

from ..cad.geometry import fan_triangles


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


from fabricate.cad.parts import GENUS

_CHECKED: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
"""``{parts: {origin bytes: facts}}``: the manifold3d checks passed by each (immutable) parts object, while it lives."""


def validate_manifold(parts, origin: np.ndarray | None = None) -> dict:
    """Check every group with manifold3d (once per parts object and origin); return facts (a copy);
    raise ExportError naming a bad part (a failed check is not remembered).

    Each part is one connected closed surface by construction (its faces share
    edges), so the group's genus ``1 - p`` means every part has genus 0.
    Facts: ``status`` ("NoError"), ``components`` (= parts), ``genus`` (= 1 - parts),
    ``volume_mm3`` (manifold3d) and ``volume_rel_error`` against the analytic sum.
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


def _validate(parts, origin: np.ndarray) -> dict:
    """:func:`validate_manifold` without the cache."""
    total, analytic, comps, genus = 0.0, 0.0, 0, 0
    for g in parts.groups:
        X, T = group_triangles(g, origin)
        m = manifold_of(X, T)
        status = m.status().name
        if status != "NoError":
            for i in range(len(g)):  # find the culprit (rare path)
                s = manifold_of(X[i:i + 1], T).status().name
                if s != "NoError":
                    raise ExportError(f"{g.ids[i]}: manifold3d rejects the solid ({s}); "
                                      "expected a closed oriented 2-manifold")
            raise ExportError(f"{g.kind} group: manifold3d status {status}")
        holes = GENUS.get(g.member, 0)   # a hub tube has one hole
        if m.genus() != 1 - len(g) + holes * len(g):  # each part one closed surface of its genus
            raise ExportError(f"{g.kind} group: manifold3d genus {m.genus()} for {len(g)} parts, "
                              f"expected {1 - len(g) + holes * len(g)} (every part a closed genus-{holes} surface)")
        total += m.volume()
        analytic += float(g.volume_mm3.sum())
        comps += len(g)
        genus += m.genus() - 1  # genus of a union of c closed surfaces is 1 - c + their genera
    return {"status": "NoError", "components": comps, "genus": genus + 1, "volume_mm3": total,
            "volume_rel_error": abs(total - analytic) / max(analytic, 1e-300)}
