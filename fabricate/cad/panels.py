"""Glass panels: every face polygon inset by half the joint gap, given a thickness.

A panel of a ``k``-gon face is a prism-like solid with ``2 k`` vertices: the
lower ring (smaller offset along the face normal) then the upper ring, and
``k + 2`` faces: lower, upper, then side ``j`` over face edge ``j``.  It lies
between the face plane at the first layer (fitted to the layer's polygon;
the glass bears on the beams there) and the plane ``glass_thickness`` away on
the side opposite the beams.  Side ``j`` lies in

- ``axis``: the plane of the beam of edge ``j`` moved ``joint_gap / 2`` into
  the face (the sides of two neighbouring panels are then parallel planes
  ``joint_gap`` apart, so they cannot clash);
- ``perpendicular``: the plane through the face edge moved ``joint_gap / 2``
  into the face, normal to the face.

Every corner is the meeting point of three planes (face plane, two sides).

A glass unit of several layers (:mod:`fabricate.cad.glass`) is a ``stack`` of
such prisms over the same side planes: ply ``i`` lies between ``offset_i`` and
``offset_i + thickness_i`` from the bearing plane on the glass side, its sides
moved ``inset_i`` further into the face (a stepped inner pane).  In ``axis``
mode the plies' sides are then coplanar across the stack; in
``perpendicular`` mode they are normal to the panel.
"""
from __future__ import annotations

import numpy as np

from .geometry import dot, meet3, plane_fit, unit


def prism_faces(k: int) -> tuple[tuple[int, ...], ...]:
    """Faces of a ``k``-gon prism: lower ring ``0..k-1``, upper ring ``k..2k-1`` (outward)."""
    lower = tuple(range(k - 1, -1, -1))
    upper = tuple(range(k, 2 * k))
    sides = tuple((j, (j + 1) % k, k + (j + 1) % k, k + j) for j in range(k))
    return (lower, upper) + sides


def panel_solids(structure, beam_planes: dict, P0: np.ndarray, thickness: float, gap: float, mode: str,
                 s_beam: float, faces: np.ndarray | None = None,
                 stack: tuple[tuple[float, float, float], ...] | None = None) -> list[dict]:
    """Panels grouped by face size (of every face, or of the mesh faces ``faces (q,)`` only).

    P0 : (n, 3) vertex positions at the first layer (the glass bears there).
    beam_planes : :func:`fabricate.cad.beams.beam_planes` of the structure.
    mode : ``axis`` | ``perpendicular``; s_beam : +1 when the beams lie on the
    normals' side of the glass, else -1.
    Returns one dict per face size ``k``: ``faces_index (p,)`` mesh faces,
    ``vertices (p, 2k, 3)``, ``normals (p, k + 2, 3)`` outward face normals,
    ``faces`` (the shared face tuple), ``edges (p, k)`` topology edge under
    each side, ``planarity_mm (p,)``, ``bearing_face`` (0 lower | 1 upper).
    stack : ``((offset, thickness, inset), ...)`` mm, the layers of a unit (default one ply
    ``(0, thickness, 0)``); each batch then has ``plies``: per layer ``{"vertices", "normals"}``
    in stack order, ``vertices`` and ``normals`` being those of the first.
    """
    stack = ((0.0, float(thickness), 0.0),) if stack is None else tuple(stack)
    mesh = structure.mesh
    topo = mesh.topology
    N = unit(np.asarray(structure.normals, dtype=float))
    sizes = mesh.face_sizes
    out = []
    chosen = np.ones(len(sizes), dtype=bool) if faces is None else np.isin(np.arange(len(sizes)), faces)
    for k in np.unique(sizes[chosen]).tolist():  # one batch per face size
        f = np.nonzero((sizes == k) & chosen)[0]
        F = mesh.F[f, :k]
        P = P0[F]                                   # (p, k, 3)
        n = N[f]
        E = topo.corner_edge[topo.offsets[f][:, None] + np.arange(k)[None, :]]  # (p, k), edge j -> j+1
        # faces turning clockwise about their normal (flipped normals): walk them backwards
        Q = P - P[:, :1]
        back = dot(np.cross(Q, np.roll(Q, -1, axis=1)).sum(axis=1), n) < 0
        P = np.where(back[:, None, None], P[:, ::-1], P)
        E = np.where(back[:, None], np.roll(E[:, ::-1], -1, axis=1), E)
        o0, dev = plane_fit(P, n)
        Pp = P - (dot(P, n[:, None, :]) - o0[:, None])[..., None] * n[:, None, :]
        mid = 0.5 * (Pp + np.roll(Pp, -1, axis=1))
        if mode == "axis":
            mu = beam_planes["normal"][E]
            outward = dot(mu, mid - Pp.mean(axis=1, keepdims=True)) >= 0
            mu = np.where(outward[..., None], mu, -mu)
            so = np.where(outward, 1.0, -1.0) * beam_planes["offset"][E] - 0.5 * gap
        elif mode == "perpendicular":
            t = unit(np.roll(Pp, -1, axis=1) - Pp)
            mu = unit(np.cross(t, n[:, None, :]))
            so = dot(mu, Pp) - 0.5 * gap
        else:
            raise ValueError(f"panel edge mode {mode!r}: expected 'axis' or 'perpendicular'")
        mu_prev = np.roll(mu, 1, axis=1)
        nk = np.broadcast_to(n[:, None, :], mu.shape)
        normals = np.concatenate([-n[:, None, :], n[:, None, :], mu], axis=1)
        plies = []
        for offset, t, inset in stack:  # one prism per layer of the unit (a few)
            o_lo = o0 - offset - t if s_beam > 0 else o0 + offset
            o_hi = o_lo + t
            si = so - inset
            si_prev = np.roll(si, 1, axis=1)
            lo, _ = meet3(nk, np.broadcast_to(o_lo[:, None], so.shape), mu_prev, si_prev, mu, si)
            hi, _ = meet3(nk, np.broadcast_to(o_hi[:, None], so.shape), mu_prev, si_prev, mu, si)
            plies.append({"vertices": np.concatenate([lo, hi], axis=1), "normals": normals})
        out.append({"k": k, "faces_index": f, "vertices": plies[0]["vertices"], "normals": normals,
                    "plies": plies, "faces": prism_faces(k), "edges": E, "planarity_mm": dev,
                    "bearing_face": 1 if s_beam > 0 else 0})
    return out
