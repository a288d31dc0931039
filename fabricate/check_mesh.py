"""The full check's mesh files: the 3MF objects and the STL, read back and held to the BOM.

Split from :mod:`fabricate.check` (the same checks, all parts at once): ``check_3mf`` (one
manifold3d mesh of every object, volumes by the divergence theorem) and ``check_stl`` (the
corners of each part welded at once, one manifold3d mesh).
"""
from __future__ import annotations

import numpy as np

from optimize.tolerances import DEFAULT, Tolerances


def _volumes(bom) -> dict[str, float]:
    return {r["id"]: float(r["volume_mm3"]) for r in bom}


def check_3mf(path, bom, tol: Tolerances = DEFAULT):
    """One manifold3d mesh of all objects (indices apart, so each stays its own surface): status
    NoError and genus ``1 - objects`` hold when every object is a closed 2-manifold of genus 0 (a
    closed surface's genus is never negative); otherwise each object alone names the bad ones.
    Volumes by the divergence theorem per object, each within ``tol.file_volume`` (relative) of the BOM's."""
    import manifold3d

    from .export.threemf_text import read_3mf_text
    from .export.verify import solids_of

    from .check import _holes

    objects = read_3mf_text(path)
    expected = _volumes(bom)
    holes = _holes(bom)  # a hub tube is a closed surface of genus 1
    missing = sorted(set(expected) - set(objects))
    extra = sorted(set(objects) - set(expected))
    solids = solids_of(objects)
    names = list(objects)
    bad, worst, worst_id, errors = [], 0.0, None, []
    if names:
        sizes = np.array([len(objects[n][0]) for n in names])
        base = np.concatenate([[0], np.cumsum(sizes)[:-1]])
        V = np.concatenate([objects[n][0] for n in names]).astype(np.float64)
        T = np.concatenate([objects[n][1] + b for n, b in zip(names, base)])
        whole = manifold3d.Manifold(manifold3d.Mesh64(vert_properties=V, tri_verts=T.astype(np.uint64)))
        genera = sum(holes.get(n, 0) for n in names)
        if whole.status().name != "NoError" or whole.genus() != 1 - len(names) + genera:
            bad = [n for n in names if solids[n].manifold.status().name != "NoError"
                   or solids[n].manifold.genus() != holes.get(n, 0)]
        obj = np.repeat(np.arange(len(names)), [len(objects[n][1]) for n in names])
        first = np.repeat(base, sizes)                                 # relative to each object's first vertex
        X = V - V[first]
        det = np.einsum("ij,ij->i", X[T[:, 0]], np.cross(X[T[:, 1]], X[T[:, 2]]))
        vol = np.bincount(obj, weights=det, minlength=len(names)) / 6.0
        for n, v in zip(names, vol.tolist()):
            if n in expected and n not in bad:
                rel = abs(v - expected[n]) / expected[n]
                if rel > worst:
                    worst, worst_id = rel, n
                if rel > tol.file_volume:
                    errors.append(n)
    split = _split_objects(list(objects.values()))
    ok = not missing and not extra and not bad and not errors and not split
    return ({"pass": ok, "objects": len(objects), "missing": missing[:20], "unexpected": extra[:20],
             "not_manifold": bad[:20], "not_one_piece": split[:20], "volume_rel_error_max": worst,
             "worst": worst_id, "volume_failures": errors[:20]}, solids)


def _split_objects(objects: list[tuple[np.ndarray, np.ndarray]]) -> list[int]:
    """Indices of the meshes ``[(V, T), ...]`` that are not one connected piece (one graph for all)."""
    if not objects:
        return []
    sizes = np.array([len(V) for V, _ in objects])
    base = np.concatenate([[0], np.cumsum(sizes)[:-1]])
    T = np.concatenate([t + b for (_, t), b in zip(objects, base)])
    labels = _components(np.zeros((int(sizes.sum()), 3)), T, labels=True)
    lo = np.minimum.reduceat(labels, base)
    hi = np.maximum.reduceat(labels, base)
    return np.nonzero(lo != hi)[0].tolist()


def check_stl(path, bom, meshes):
    import manifold3d

    from .export.stl import read_stl

    P, header = read_stl(path)
    order = [r["id"] for r in bom]
    counts = [len(meshes[i].T) if i in meshes else -1 for i in order]
    if min(counts, default=0) < 0 or sum(counts) != len(P):
        return {"pass": False, "error": f"{len(P)} triangles in the STL, {sum(counts)} in the 3MF parts "
                                        "(or a part is missing); expected the same triangles"}
    V, T = _weld_parts(P, np.asarray(counts))
    m = manifold3d.Manifold(manifold3d.Mesh(vert_properties=V, tri_verts=T.astype(np.uint32)))
    status = m.status().name
    comps = _components(V, T)
    analytic = sum(_volumes(bom).values())
    A = P.astype(float)
    area = 0.5 * float(np.linalg.norm(np.cross(A[:, 1] - A[:, 0], A[:, 2] - A[:, 0]), axis=1).sum())
    bound = 4 * float(np.finfo(np.float32).eps) * float(np.abs(A).max()) * area
    dv = abs(m.volume() - analytic)
    from .check import _holes

    expected_genus = 1 - len(order) + sum(_holes(bom).values())  # hub tubes have genus 1
    ok = status == "NoError" and comps == len(order) and m.genus() == expected_genus and dv <= bound
    return {"pass": ok, "status": status, "triangles": len(P), "components": comps, "parts": len(order),
            "genus": int(m.genus()), "expected_genus": expected_genus, "volume_mm3": m.volume(),
            "volume_error_mm3": dv, "float32_bound_mm3": bound, "origin_mm": header["origin"].tolist()}


def _weld_parts(P: np.ndarray, counts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each part's triangle corners welded where they are equal (float32, exactly; -0 is 0), parts
    kept apart: ``(V (n, 3) float32, T (t, 3) int)`` from ``P (t, 3, 3)`` and triangles per part."""
    X = P.reshape(-1, 3).astype(np.float32) + np.float32(0.0)          # -0.0 + 0.0 = +0.0
    part = np.repeat(np.arange(len(counts), dtype=np.uint64), 3 * counts)
    bits = X.view(np.uint32).astype(np.uint64)
    k1 = (part << np.uint64(32)) | bits[:, 0]
    k2 = (bits[:, 1] << np.uint64(32)) | bits[:, 2]
    order = np.lexsort((k2, k1))
    new = np.ones(len(order), bool)
    new[1:] = (k1[order][1:] != k1[order][:-1]) | (k2[order][1:] != k2[order][:-1])
    idx = np.cumsum(new) - 1
    inv = np.empty(len(order), np.int64)
    inv[order] = idx
    return X[order[new]], inv.reshape(-1, 3)


def _components(V: np.ndarray, T: np.ndarray, labels: bool = False):
    """Number of connected components of a triangle mesh (vertex graph through triangle edges),
    or the component label of every vertex ``(n,)`` with ``labels``."""
    import scipy.sparse as sp
    from scipy.sparse.csgraph import connected_components

    a = np.concatenate([T[:, 0], T[:, 1], T[:, 2]])
    b = np.concatenate([T[:, 1], T[:, 2], T[:, 0]])
    G = sp.coo_matrix((np.ones(len(a)), (a, b)), shape=(len(V), len(V)))
    n, lab = connected_components(G, directed=False)
    return lab if labels else int(n)
