"""Flat data of a part cut from sheet: its true outline, the bevel of every edge, and its placement.

A part cut from sheet of thickness ``t`` is described in its own frame (the
*part frame*, mm): the sheet lies between ``z = -t`` and ``z = 0``, ``z = 0``
being the part's reference face (panel: the face bearing on the beams; beam:
its ``+`` plate face), seen from outside (``+z``).  In that frame:

- ``outline (p, k, 2)``: the polygon the shop cuts, counter-clockwise: for a
  panel the bearing face, for a beam its full profile, the V-shaped ends
  reaching the node axes and the ridge under the glass included (the corners
  of the planar beam quad, which are the solid's outermost edges);
- ``outline_z (p, k)``: the height of each outline corner (panel ``0``; beam
  about ``-t / 2``: the ridge and the V tips are at mid-thickness);
- ``bevel_deg (p, k, 2)``: for every outline edge ``j -> j + 1`` the angle from
  square of the cut face on the ``+z`` side and on the ``-z`` side, positive
  when the part gets narrower from the outline edge toward that face (a V end
  or a ridge: both positive; a glass edge with one bevel through the whole
  thickness: ``[b, -b]``);
- ``transform (p, 4, 4)``: part frame -> model (mm), a rigid motion.

The cut face of edge ``j`` on side ``s`` (``s_z = +1 | -1``) is the plane
through the outline edge at its corner heights whose outward normal is
``cos(b) m + s_z sin(b) z + tau t`` (``m`` outward in-plane normal of the edge,
``t`` along it, ``tau`` the component that keeps the edge in the plane).  The
part is the sheet slab intersected with these half-spaces: the outline
thickened, bevelled and placed by its transform is the solid
(:func:`solid_halfspaces`, :func:`reconstruct`; ``fabricate check`` compares
them with the STEP solid).
"""
from __future__ import annotations

import numpy as np

from .geometry import dot, min_area_rectangle, rotate2d, unit


def edge_cuts(faces: tuple[tuple[int, ...], ...], ring: tuple[int, ...], top: int, bottom: int) -> np.ndarray:
    """(k, 2) int: the face cut along each outline edge ``ring[j] -> ring[j+1]``, [``+z`` side, ``-z`` side].

    Combinatorial (one face list per group).  An edge on one face besides the
    slab faces (a bevel through the whole thickness) uses it for both sides;
    an edge on two (a V or a ridge) uses the one sharing a vertex with ``top``
    for the ``+z`` side.
    """
    top_v = set(faces[top])
    k = len(ring)
    out = np.empty((k, 2), dtype=np.int64)
    for j in range(k):  # combinatorics of one group, not per part
        a, b = ring[j], ring[(j + 1) % k]
        on = [fi for fi, f in enumerate(faces) if fi not in (top, bottom) and a in f and b in f]
        if len(on) == 1:
            out[j] = on[0]
        elif len(on) == 2:
            plus = on[0] if top_v & set(faces[on[0]]) else on[1]
            out[j] = (plus, on[1] if plus == on[0] else on[0])
        else:
            raise ValueError(f"outline edge {a}-{b}: on {len(on)} cut faces, expected 1 or 2")
    return out


def flat_data(V: np.ndarray, normals: np.ndarray, faces, ring: tuple[int, ...], top: int, bottom: int) -> dict:
    """The flat data of ``p`` solids of one combinatorial type.

    V : (p, nv, 3) vertices; normals : (p, nf, 3) outward face normals;
    ring : vertex indices of the outline (counter-clockwise seen from outside
    ``top``); top, bottom : the slab faces (reference face, opposite face).
    Returns ``outline (p, k, 2)``, ``outline_z (p, k)``, ``bevel_deg (p, k, 2)``,
    ``transform (p, 4, 4)``, ``rect (p, 2)`` (width >= height of a rectangle
    holding every vertex), ``top_flat (p, kt, 2)``, ``bottom_flat (p, kb, 2)``
    (the two slab faces in the part frame), ``cuts (k, 2)`` (:func:`edge_cuts`),
    ``thickness (p,)`` (distance between the slab faces).
    """
    z = unit(normals[:, top])
    ref = V[:, list(faces[top])]
    origin = ref[:, 0]
    ex = unit(ref[:, 1] - ref[:, 0])
    ex = unit(ex - dot(ex, z)[:, None] * z)
    ey = np.cross(z, ex)
    D = V - origin[:, None, :]
    P2 = np.stack([dot(D, ex[:, None, :]), dot(D, ey[:, None, :])], axis=2)   # (p, nv, 2)
    H = dot(D, z[:, None, :])                                                 # (p, nv)
    ring_l = list(ring)
    both = np.concatenate([P2[:, ring_l], P2[:, list(faces[top])], P2[:, list(faces[bottom])]], axis=1)
    ang, _, _ = min_area_rectangle(P2[:, ring_l] if len(ring) >= 3 else both)
    ext = np.ptp(rotate2d(P2, ang), axis=1)
    ang = np.where(ext[:, 1] > ext[:, 0], ang + np.pi / 2, ang)     # landscape over every vertex
    R = rotate2d(P2, ang)
    low = R.min(axis=1)
    R = R - low[:, None, :]
    rect = R.max(axis=1)
    c, s = np.cos(ang), np.sin(ang)
    ux = c[:, None] * ex - s[:, None] * ey          # part-frame x, y in the model
    uy = s[:, None] * ex + c[:, None] * ey
    M = np.zeros((len(V), 4, 4))
    M[:, :3, 0], M[:, :3, 1], M[:, :3, 2] = ux, uy, z
    M[:, :3, 3] = origin + low[:, :1] * ux + low[:, 1:] * uy
    M[:, 3, 3] = 1.0
    outline, oz = R[:, ring_l], H[:, ring_l]
    cuts = edge_cuts(faces, ring, top, bottom)
    nu = normals[:, cuts.ravel()].reshape(len(V), len(ring), 2, 3)               # (p, k, 2, 3)
    nl = np.stack([dot(nu, ux[:, None, None, :]), dot(nu, uy[:, None, None, :]), dot(nu, z[:, None, None, :])],
                  axis=-1)
    E = np.roll(outline, -1, axis=1) - outline
    m = unit(np.stack([E[..., 1], -E[..., 0], np.zeros(E.shape[:2])], axis=-1))   # outward, CCW outline
    a = dot(nl, m[:, :, None, :])
    sz = np.array([1.0, -1.0])
    bevel = np.degrees(np.arctan2(sz * nl[..., 2], a))
    thickness = -dot(V[:, faces[bottom][0]] - origin, z)
    cut = silhouette(outline, oz, bevel, thickness)
    more = np.minimum(cut.min(axis=1), 0.0)        # a blank corner beyond the vertices: shift the frame
    cut, outline, R = cut - more[:, None], outline - more[:, None], R - more[:, None]
    M[:, :3, 3] += more[:, :1] * ux + more[:, 1:] * uy
    rect = np.maximum(R.max(axis=1), cut.max(axis=1))
    return {"outline": cut, "ref": outline, "ref_z": oz, "bevel_deg": bevel, "transform": M, "rect": rect,
            "top_flat": R[:, list(faces[top])], "bottom_flat": R[:, list(faces[bottom])], "cuts": cuts,
            "thickness": thickness}


def cut_planes(ref: np.ndarray, ref_z: np.ndarray, bevel_deg: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Outward normals ``(p, k, 2, 3)`` and offsets ``(p, k, 2)`` (``n . x = o``) of the cut faces, part frame.

    ref (p, k, 2), ref_z (p, k), bevel_deg (p, k, 2): the bevel reference
    outline, its corner heights and the bevel angles of :func:`flat_data`.
    """
    p, k = ref.shape[:2]
    P = np.concatenate([ref, ref_z[..., None]], axis=2)
    d = np.roll(P, -1, axis=1) - P
    L = np.linalg.norm(d[..., :2], axis=2)
    L = np.where(L > 0, L, 1.0)
    t = np.concatenate([d[..., :2] / L[..., None], np.zeros((p, k, 1))], axis=2)
    m = np.stack([t[..., 1], -t[..., 0], np.zeros((p, k))], axis=-1)
    b = np.radians(bevel_deg)
    sz = np.array([1.0, -1.0])
    ez = np.array([0.0, 0.0, 1.0])
    n = (np.cos(b)[..., None] * m[:, :, None, :] + (sz * np.sin(b))[..., None] * ez
         - (sz * np.sin(b) * (d[..., 2] / L)[..., None])[..., None] * t[:, :, None, :])
    n = unit(n)
    return n, dot(n, P[:, :, None, :])


def silhouette(ref: np.ndarray, ref_z: np.ndarray, bevel_deg: np.ndarray, thickness: np.ndarray) -> np.ndarray:
    """(p, k, 2): the outline to cut from sheet: per edge, the reference line moved out to the farthest of
    itself and the lines where its two cut faces meet the sheet faces, measured at both ends of the edge
    (a ridge: the reference line; a valley or an edge leaning out: a sheet face's edge), consecutive
    lines intersected.  It holds the whole part; at a corner between edges leaning opposite ways it
    passes a little outside the part (ground off with the bevel)."""
    n, o = cut_planes(ref, ref_z, bevel_deg)
    p, k = ref.shape[:2]
    E = np.roll(ref, -1, axis=1) - ref
    m = unit(np.stack([E[..., 1], -E[..., 0]], axis=-1))
    # 2D lines n2 . x = o - nz z at the sheet faces; their distance beyond the reference line along m
    best = np.zeros((p, k))
    for s, z in ((0, np.zeros(p)), (1, -thickness)):  # two sides of the sheet
        n2, nz = n[:, :, s, :2], n[:, :, s, 2]
        oz = o[:, :, s] - nz * z[:, None]
        along = dot2(n2, m)
        for at in (ref, np.roll(ref, -1, axis=1)):  # both ends: the face line may not be parallel (twist)
            shift = (oz - dot2(n2, at)) / np.where(np.abs(along) > 1e-12, along, 1.0)
            best = np.maximum(best, np.where(np.abs(along) > 1e-12, shift, 0.0))
    c = dot2(m, ref) + best                               # lines m . x = c
    c_prev, m_prev = np.roll(c, 1, axis=1), np.roll(m, 1, axis=1)
    det = m_prev[..., 0] * m[..., 1] - m_prev[..., 1] * m[..., 0]
    x = (c_prev * m[..., 1] - c * m_prev[..., 1]) / np.where(np.abs(det) > 1e-300, det, 1.0)
    y = (m_prev[..., 0] * c - m[..., 0] * c_prev) / np.where(np.abs(det) > 1e-300, det, 1.0)
    return np.stack([x, y], axis=2)


def dot2(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return a[..., 0] * b[..., 0] + a[..., 1] * b[..., 1]


def face_planes(ref, ref_z, bevel_deg, thickness, cuts: np.ndarray, n_faces: int, top: int, bottom: int,
                transform: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Every face plane of the solid the flat data describe, in the model: normals ``(p, nf, 3)``,
    offsets ``(p, nf)``.  The sheet faces are ``z = 0`` (``top``) and ``z = -thickness`` (``bottom``);
    face ``cuts[j, s]`` is the cut of edge ``j`` on side ``s``."""
    n, o = cut_planes(ref, ref_z, bevel_deg)
    p = len(ref)
    N = np.zeros((p, n_faces, 3))
    O = np.zeros((p, n_faces))
    for s in (1, 0):  # a face on both sides (a bevel through the thickness): either gives the plane
        N[:, cuts[:, s]] = n[:, :, s]
        O[:, cuts[:, s]] = o[:, :, s]
    N[:, top], O[:, top] = (0.0, 0.0, 1.0), 0.0
    N[:, bottom], O[:, bottom] = (0.0, 0.0, -1.0), thickness
    R, t = transform[:, :3, :3], transform[:, :3, 3]
    Nw = np.einsum("pij,pfj->pfi", R, N)
    return Nw, O + dot(Nw, t[:, None, :])


def corner_triples(faces, normals: np.ndarray) -> np.ndarray:
    """(p, nv, 3) int: for every corner of every solid three of its faces meeting at the best angle.

    faces : the group's face tuples; normals : (p, nf, 3) face normals (of the solid or of its
    reconstruction: a corner on four faces, two of them coplanar, takes the other two).
    """
    from itertools import combinations

    nv = 1 + max(max(f) for f in faces)
    out = np.empty((len(normals), nv, 3), dtype=np.int64)
    for v in range(nv):  # combinatorics of one group; the choice is vectorized over solids
        inc = [fi for fi, f in enumerate(faces) if v in f]
        cand = np.asarray(list(combinations(inc, 3)), dtype=np.int64)        # (c, 3)
        det = np.abs(np.linalg.det(normals[:, cand]))                        # (p, c)
        out[:, v] = cand[np.argmax(det, axis=1)]
    return out


def solid_from_flat(N: np.ndarray, O: np.ndarray, triples: np.ndarray, ring, ref: np.ndarray, ref_z: np.ndarray,
                    transform: np.ndarray) -> np.ndarray:
    """(p, nv, 3): the solid's corners from its flat data, in the model.

    The reference outline's corners (``ring``, from ``ref (p, k, 2)`` at ``ref_z (p, k)``) are placed by
    ``transform``; every other corner is where the face planes ``N (p, nf, 3)``, ``O (p, nf)`` meet,
    three per corner as ``triples (p, nv, 3)`` say.
    """
    from .geometry import meet3

    i = np.arange(len(N))[:, None]
    a, b, c = triples[..., 0], triples[..., 1], triples[..., 2]
    X, _ = meet3(N[i, a], O[i, a], N[i, b], O[i, b], N[i, c], O[i, c])
    P = np.concatenate([ref, ref_z[..., None]], axis=2)
    X[:, list(ring)] = np.einsum("pij,pkj->pki", transform[:, :3, :3], P) + transform[:, None, :3, 3]
    return X
