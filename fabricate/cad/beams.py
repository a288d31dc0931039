"""Beams: the planar beam quad of every edge, thickened and trimmed at its nodes.

For an edge ``(a, b)`` the offset stage gives the quad ``[A0, B0, B1, A1]``
between the first and last layer (``A0``, ``A1`` on the axis of node ``a``).
The beam is a plate cut from flat stock: the polyhedron bounded by ten planes:

- ``F+``, ``F-``: the beam plane (fitted to the quad) moved by
  ``+-beam_width / 2``;
- ``T0+``, ``T0-``: through the edge ``A0 B0``, tilted like the face on that
  side (for a conical mesh: exactly the face planes at the first layer, so the
  glass bears on them); ``T1+-`` the same at the last layer;
- ``Ea+``, ``Ea-`` at node ``a`` (``Eb+-`` at ``b``): without nodes, the
  bisector planes, through the node axis, between this beam and its angular
  neighbour on each side (so neighbouring beams meet in one plane and never
  overlap; a side with no neighbour within 180 degrees gets a square end);
  with square ends (a hub, ``parts.node.connection: none``), one plane normal
  to the beam, set back from the axis by the hub radius or gap or more
  (enough that neighbours as wide as the section's flanges cannot touch).

The flanges and the second web of a section (:mod:`fabricate.cad.sections`)
are cut from the same planes (returned as ``planes``).

The centre line corners are the quad's own corners, on the node axes: the
end planes are hinged on the node axis itself (the same line, computed from
the same numbers, for every beam of a node), so two neighbouring beams share
their bisector plane exactly even where the quad is twisted (a PQ mesh that
is not conical, boundary nodes, strips).  A twisted quad is then not in its
plate's mid-plane: the BOM reports how far (``planarity_mm``), and the
plate stays flat.

Vertices (12, in this order) and faces (10 quads, outward) in the beam frame
``x`` = along ``a -> b``, ``y`` = beam normal (``+`` side), ``z`` = toward the
first layer::

    0 A0  1 B0  2 B1  3 A1         centre line (on the node axes)
    4 A0+ 5 B0+ 6 B1+ 7 A1+        + side
    8 A0- 9 B0- 10 B1- 11 A1-      - side

Every vertex is the meeting point of three of these planes (the centre ones:
of an edge line and the end planes through the axis), so every face is
planar up to round-off.
"""
from __future__ import annotations

import numpy as np

from .geometry import dot, line_plane, meet3, unit

FACES = ((4, 5, 6, 7), (8, 11, 10, 9), (0, 1, 5, 4), (0, 8, 9, 1), (3, 7, 6, 2), (3, 2, 10, 11),
         (0, 4, 7, 3), (0, 3, 11, 8), (1, 2, 6, 5), (1, 9, 10, 2))
FACE_NAMES = ("F+", "F-", "T0+", "T0-", "T1+", "T1-", "Ea+", "Ea-", "Eb+", "Eb-")
OUTLINE_FACE, BEVEL_FACE = 0, 1
RING = (0, 1, 2, 3)
"""The flat outline of a beam: its centre line corners (the ridge under the glass, the V tips on the
node axes, the bottom ridge), counter-clockwise seen from the ``+`` side; edge 0 is the glass side."""


def beam_planes(structure) -> dict[str, np.ndarray]:
    """The plane of every beam (its plate's mid-plane), its quad, and a right-handed frame.

    Returns a dict of arrays (``e`` edges):
    ``quad (e, 4, 3)`` [A0, B0, B1, A1] as given (corners on the node axes);
    ``normal (e, 3)`` unit, oriented so that ``(B0 - A0) x normal`` points from
    the last layer toward the first; ``offset (e,)`` (``normal . x = offset``,
    the plane through the quad's centroid); ``planarity_mm (e,)`` the largest
    distance of a quad corner from that plane (0 for a torsion-free beam).
    """
    Q = np.asarray(structure.beam_quads, dtype=float)
    n = unit(np.asarray(structure.beam_normals, dtype=float))
    c = Q.mean(axis=1)
    h = dot(Q - c[:, None, :], n[:, None, :])
    along = Q[:, 1] - Q[:, 0] + Q[:, 2] - Q[:, 3]
    up = Q[:, 0] - Q[:, 3] + Q[:, 1] - Q[:, 2]
    flip = dot(np.cross(along, n), up) < 0
    n = np.where(flip[:, None], -n, n)
    return {"quad": Q, "normal": n, "offset": dot(n, c), "planarity_mm": np.abs(h).max(axis=1)}


def _node_frames(axes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors ``(n, 3)`` completing each axis to a right-handed frame."""
    helper = np.where((np.abs(axes[:, 0]) < 0.9)[:, None], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0])
    x = unit(np.cross(helper, axes))
    return x, np.cross(axes, x)


def angular_neighbours(structure, P0: np.ndarray, normal: np.ndarray) -> dict[str, np.ndarray]:
    """Gaps to the neighbouring beams around each node axis, per beam end.

    P0 : (n, 3) vertex positions at the first layer; normal : (e, 3) oriented
    beam normals (:func:`beam_planes`).
    Returns ``gap (e, 2, 2)`` radians ``[end a|b, side +|-]`` (2 pi when the
    node has one beam) and ``beam (e, 2, 2)`` the neighbouring edge index.
    """
    E = np.asarray(structure.edges)
    V = P0
    axes = unit(np.asarray(structure.axes, dtype=float))
    ne = len(E)
    node = E.T.ravel()                      # end a of every edge, then end b
    other = E[:, ::-1].T.ravel()
    edge = np.tile(np.arange(ne), 2)
    a = axes[node]
    d = V[other] - V[node]
    d = d - dot(d, a)[:, None] * a
    fx, fy = _node_frames(axes)
    ang = np.arctan2(dot(d, fy[node]), dot(d, fx[node]))
    order = np.lexsort((ang, node))
    nd, an = node[order], ang[order]
    start = np.searchsorted(nd, nd, side="left")
    stop = np.searchsorted(nd, nd, side="right")
    size = stop - start
    pos = np.arange(len(order))
    nxt = start + (pos - start + 1) % size
    prv = start + (pos - start - 1) % size
    two_pi = 2 * np.pi
    gap_next = np.where(size > 1, (an[nxt] - an) % two_pi, two_pi)
    gap_prev = np.where(size > 1, (an - an[prv]) % two_pi, two_pi)
    # does increasing angle turn toward the + side (the oriented beam normal)?
    toward_plus = dot(np.cross(a[order], d[order]), normal[edge[order]]) > 0
    gap = np.empty((len(order), 2))
    nb = np.empty((len(order), 2), dtype=np.int64)
    gap[order, 0] = np.where(toward_plus, gap_next, gap_prev)
    gap[order, 1] = np.where(toward_plus, gap_prev, gap_next)
    nb[order, 0] = edge[order][np.where(toward_plus, nxt, prv)]
    nb[order, 1] = edge[order][np.where(toward_plus, prv, nxt)]
    return {"gap": gap.reshape(2, ne, 2).transpose(1, 0, 2), "beam": nb.reshape(2, ne, 2).transpose(1, 0, 2)}


def _end_planes(A0, A1, toward, n, alpha, setback):
    """Outward end planes ``(normal (e, 2, 3), offset (e, 2))`` [side +, -] at one end.

    A0, A1 : (e, 3) the node at the first and last layer (the end line is the
    node axis through them); toward : (e, 3) from this node to the other end
    of the beam; n : (e, 3) oriented beam normal (which side is ``+``);
    alpha : (e, 2) half gaps (<= pi / 2); setback : (e,) or None.

    The frame is built from the node axis and the direction to the other node
    only (``u`` along the beam normal to the axis, ``w = ell x u`` turned to the
    ``+`` side), so the bisector plane a beam computes at a node is the plane
    its neighbour computes there, whatever the twist of either beam.
    """
    ell = unit(A1 - A0)
    u = unit(toward - dot(toward, ell)[:, None] * ell)
    w = np.cross(ell, u)
    n = np.where((dot(w, n) < 0)[:, None], -w, w)
    if setback is None:
        sa, ca = np.sin(alpha), np.cos(alpha)
        nu_p = -sa[:, :1] * u + ca[:, :1] * n
        nu_m = -sa[:, 1:] * u - ca[:, 1:] * n
        nu = np.stack([nu_p, nu_m], axis=1)
        off = dot(nu, A0[:, None, :])
    else:
        nu = np.repeat(-u[:, None, :], 2, axis=1)
        off = dot(nu, (A0 + setback[:, None] * u)[:, None, :])
    return nu, off


def beam_solids(structure, P0: np.ndarray, width: float, node_radius: float, s_beam: float,
                half_width: float | None = None, square: bool | None = None) -> dict:
    """Vertices and face planes of every beam (its plate, or the web of a section).

    P0 : (n, 3) vertex positions at the first layer (glass side).
    width : plate (web) width (mm); node_radius : the least distance of square
    ends from the node axis (a hub radius, the gap of ``none``);
    s_beam : +1 when the last layer lies on the normals' side of the first,
    else -1; half_width : the section's half width across the beam plane
    (flanges), default ``width / 2``: square ends are set back far enough that
    neighbours this wide cannot touch; square : square ends (default
    ``node_radius > 0``), else bisector ends.
    Returns ``vertices (e, 12, 3)``, ``normals (e, 10, 3)`` (outward, in the
    order of :data:`FACES`), ``planarity_mm (e,)``, ``setback (e, 2)`` mm
    (the distance of the end planes from the node axes, 0 for bisectors),
    ``neighbour_beams (e, 2, 2)``, ``faces (e, 2)`` (the mesh face on the
    ``+`` and ``-`` side; the same face twice on the boundary), ``planes``:
    the bounding planes as ``name -> (normal (e, 3), offset (e,))`` (outward
    for the plate: ``F+ F- T0+ T0- T1+ T1- Ea+ Ea- Eb+ Eb-``) and ``mid``
    (the beam plane, normal toward ``+``), from which
    :mod:`fabricate.cad.sections` cuts the flanges.
    """
    bp = beam_planes(structure)
    Q, n, off = bp["quad"], bp["normal"], bp["offset"]
    A0, B0, B1, A1 = Q[:, 0], Q[:, 1], Q[:, 2], Q[:, 3]
    mesh = structure.mesh
    topo = mesh.topology
    N = np.asarray(structure.normals, dtype=float)
    # faces on the + and - side of every beam plane
    ef = topo.edge_faces
    f1 = np.where(ef[:, 1] >= 0, ef[:, 1], ef[:, 0])
    cent = np.stack([_face_centroids(mesh)[ef[:, 0]], _face_centroids(mesh)[f1]], axis=1)
    side0 = dot(cent[:, 0] - A0, n) >= dot(cent[:, 1] - A0, n)
    f_plus = np.where(side0, ef[:, 0], f1)
    f_minus = np.where(side0, f1, ef[:, 0])
    # ridge planes: through the edge line, tilted like the face on that side; outward
    def ridge(P, R, f, outward_sign):
        t = unit(R - P)
        m = N[f] - dot(N[f], t)[:, None] * t
        m = unit(outward_sign * m)
        return m, dot(m, P)
    T0p, t0p = ridge(A0, B0, f_plus, -s_beam)
    T0m, t0m = ridge(A0, B0, f_minus, -s_beam)
    T1p, t1p = ridge(A1, B1, f_plus, s_beam)
    T1m, t1m = ridge(A1, B1, f_minus, s_beam)
    # end planes
    nb = angular_neighbours(structure, P0, n)
    alpha = np.minimum(nb["gap"] / 2, np.pi / 2)
    square = node_radius > 0 if square is None else square
    half_width = 0.5 * width if half_width is None else half_width
    if square:
        tan_min = np.tan(np.minimum(alpha[..., 0], alpha[..., 1]))
        need = np.where(tan_min > 1e-12, half_width / np.maximum(tan_min, 1e-12), np.inf)
        setback = np.maximum(node_radius, need)
    else:
        setback = np.zeros((len(Q), 2))
    sb = (lambda i: setback[:, i]) if square else (lambda i: None)
    Ea, ea = _end_planes(A0, A1, B0 - A0, n, alpha[:, 0], sb(0))
    Eb, eb = _end_planes(B0, B1, A0 - B0, n, alpha[:, 1], sb(1))
    half = 0.5 * width
    Fp, fp = n, off + half
    Fm, fm = -n, -off + half
    X = np.empty((len(Q), 12, 3))
    X[:, 0] = line_plane(A0, B0 - A0, Ea[:, 0], ea[:, 0])
    X[:, 1] = line_plane(A0, B0 - A0, Eb[:, 0], eb[:, 0])
    X[:, 2] = line_plane(A1, B1 - A1, Eb[:, 0], eb[:, 0])
    X[:, 3] = line_plane(A1, B1 - A1, Ea[:, 0], ea[:, 0])
    X[:, 4], _ = meet3(T0p, t0p, Fp, fp, Ea[:, 0], ea[:, 0])
    X[:, 5], _ = meet3(T0p, t0p, Fp, fp, Eb[:, 0], eb[:, 0])
    X[:, 6], _ = meet3(T1p, t1p, Fp, fp, Eb[:, 0], eb[:, 0])
    X[:, 7], _ = meet3(T1p, t1p, Fp, fp, Ea[:, 0], ea[:, 0])
    X[:, 8], _ = meet3(T0m, t0m, Fm, fm, Ea[:, 1], ea[:, 1])
    X[:, 9], _ = meet3(T0m, t0m, Fm, fm, Eb[:, 1], eb[:, 1])
    X[:, 10], _ = meet3(T1m, t1m, Fm, fm, Eb[:, 1], eb[:, 1])
    X[:, 11], _ = meet3(T1m, t1m, Fm, fm, Ea[:, 1], ea[:, 1])
    normals = np.stack([Fp, Fm, T0p, T0m, T1p, T1m, Ea[:, 0], Ea[:, 1], Eb[:, 0], Eb[:, 1]], axis=1)
    planes = dict(zip(FACE_NAMES, ((Fp, fp), (Fm, fm), (T0p, t0p), (T0m, t0m), (T1p, t1p), (T1m, t1m),
                                   (Ea[:, 0], ea[:, 0]), (Ea[:, 1], ea[:, 1]), (Eb[:, 0], eb[:, 0]),
                                   (Eb[:, 1], eb[:, 1]))))
    planes["mid"] = (n, off)
    return {"vertices": X, "normals": normals, "planarity_mm": bp["planarity_mm"],
            "setback": setback, "neighbour_beams": nb["beam"], "faces": np.stack([f_plus, f_minus], axis=1),
            "planes": planes}


def _face_centroids(mesh) -> np.ndarray:
    """(m, 3) float: vertex mean of every face."""
    valid = mesh.F >= 0
    P = mesh.V[np.maximum(mesh.F, 0)] * valid[..., None]
    return P.sum(axis=1) / valid.sum(axis=1)[:, None]
