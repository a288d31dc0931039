"""The full check's mesh files: the 3MF objects and the STL, read back and held to the BOM.

Split from :mod:`fabricate.check` (the same checks, all parts at once): ``check_3mf`` (one
manifold3d mesh per topology, the objects' volumes by the divergence theorem) and ``check_stl`` (the
corners of each part welded, runs of whole parts sorted at once, one manifold3d mesh).
"""
from __future__ import annotations

from itertools import pairwise

import numpy as np

from optimize.tolerances import DEFAULT, Tolerances

CHUNK = 1 << 15
"""Triangles per chunk of the 3MF volumes and the STL's areas (each row's figures are the same in any chunk)."""


WELD = 1 << 16
"""Corners per run of whole parts sorted at once when the STL's corners are welded."""


def _volumes(bom) -> dict[str, float]:
    return {r["id"]: float(r["volume_mm3"]) for r in bom}


def check_3mf(path, bom, tol: Tolerances = DEFAULT):
    """Every object a closed 2-manifold of its genus (0; 1 for a hub tube), one connected piece, and
    its volume (divergence theorem) within ``tol.file_volume`` (relative) of the BOM's.

    manifold3d's status and genus, and the connected pieces, depend on the triangles' vertex indices
    only (they are the topology; the coordinates do not enter): they are found once per topology
    (:func:`_topologies`: the objects with the same vertex count and triangle array; a design has
    a few, one per kind of part), on the first object that has it, and hold for all its objects."""
    import manifold3d

    from .check import _holes
    from .export.threemf_text import read_3mf_text
    from .export.verify import solids_of

    objects = read_3mf_text(path)
    expected = _volumes(bom)
    holes = _holes(bom)  # a hub tube is a closed surface of genus 1
    missing = sorted(set(expected) - set(objects))
    extra = sorted(set(objects) - set(expected))
    solids = solids_of(objects)
    names = list(objects)
    meshes = list(objects.values())
    bad, worst, worst_id, errors, split = [], 0.0, None, [], []
    if names:
        flawed: list[int] = []
        for group in _topologies(meshes):
            V, T = meshes[group[0]]
            m = manifold3d.Manifold(manifold3d.Mesh64(vert_properties=np.ascontiguousarray(V, dtype=np.float64),
                                                      tri_verts=np.ascontiguousarray(T, dtype=np.uint64)))
            fine, genus = m.status().name == "NoError", m.genus()
            flawed += [k for k in group if not fine or genus != holes.get(names[k], 0)]
            if len(V) and np.ptp(_components(V, T, labels=True)) != 0:
                split += group
        bad = [names[k] for k in sorted(flawed)]
        split.sort()
        sizes = np.array([len(V) for V, _ in meshes])
        base = np.concatenate([[0], np.cumsum(sizes)[:-1]])
        V = np.concatenate([V for V, _ in meshes]).astype(np.float64, copy=False)
        T = np.concatenate([t + b for (_, t), b in zip(meshes, base)])
        obj = np.repeat(np.arange(len(names)), [len(t) for _, t in meshes])
        first = np.repeat(base, sizes)                                 # relative to each object's first vertex
        X = V - V[first]
        det = np.empty(len(T))
        for i in range(0, len(T), CHUNK):                              # cache-sized temporaries
            t = T[i:i + CHUNK]
            det[i:i + CHUNK] = np.einsum("ij,ij->i", X[t[:, 0]], np.cross(X[t[:, 1]], X[t[:, 2]]))
        vol = np.bincount(obj, weights=det, minlength=len(names)) / 6.0
        flawed_names = set(bad)
        for n, v in zip(names, vol.tolist()):
            if n in expected and n not in flawed_names:
                rel = abs(v - expected[n]) / expected[n]
                if rel > worst:
                    worst, worst_id = rel, n
                if not rel <= tol.file_volume:   # NaN (no shape) fails
                    errors.append(n)
    ok = not missing and not extra and not bad and not errors and not split
    return ({"pass": ok, "objects": len(objects), "missing": missing[:20], "unexpected": extra[:20],
             "not_manifold": bad[:20], "not_one_piece": split[:20], "volume_rel_error_max": worst,
             "worst": worst_id, "volume_failures": errors[:20]}, solids)


def _topologies(meshes: list[tuple[np.ndarray, np.ndarray]]) -> list[list[int]]:
    """Indices of the meshes ``[(V (nv, 3), T (t, 3)), ...]`` grouped by topology: the same vertex
    count and the same triangle index array ``T``, in the order of their first mesh."""
    groups: dict[tuple, list[int]] = {}
    for k, (V, T) in enumerate(meshes):
        groups.setdefault((len(V), T.shape, T.dtype.str, T.tobytes()), []).append(k)
    return list(groups.values())


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
    norms = np.empty(len(P))
    for i in range(0, len(P), CHUNK):                                  # cache-sized temporaries
        A = P[i:i + CHUNK].astype(float)
        norms[i:i + CHUNK] = np.linalg.norm(np.cross(A[:, 1] - A[:, 0], A[:, 2] - A[:, 0]), axis=1)
    area = 0.5 * float(norms.sum())
    bound = 4 * float(np.finfo(np.float32).eps) * float(np.abs(P).max()) * area
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
    order = np.empty(len(X), np.int64)
    ends = 3 * np.cumsum(counts, dtype=np.int64)                       # the part is the first key: sorted
    cut = np.concatenate([[0], ends[np.searchsorted(ends, np.arange(WELD, len(X), WELD))], [len(X)]])
    for a, b in pairwise(np.unique(cut).tolist()):                     # a run of whole parts at a time
        order[a:b] = a + np.lexsort((k2[a:b], k1[a:b]))
    s1, s2 = k1[order], k2[order]
    new = np.ones(len(order), bool)
    new[1:] = (s1[1:] != s1[:-1]) | (s2[1:] != s2[:-1])
    idx = np.cumsum(new) - 1
    inv = np.empty(len(order), np.int64)
    inv[order] = idx
    return X[order[new]], inv.reshape(-1, 3)


def _components(V: np.ndarray, T: np.ndarray, labels: bool = False):
    """Number of connected components of a triangle mesh (vertex graph through triangle edges),
    or the component label of every vertex ``(n,)`` with ``labels``."""
    import scipy.sparse as sp
    from scipy.sparse.csgraph import connected_components

    a = np.concatenate([T[:, 0], T[:, 1]])                            # two edges join a triangle's corners
    b = np.concatenate([T[:, 1], T[:, 2]])
    G = sp.coo_matrix((np.ones(len(a), np.int8), (a, b)), shape=(len(V), len(V)))
    n, lab = connected_components(G, directed=False)
    return lab if labels else int(n)
