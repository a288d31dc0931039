"""Focal meshes and the spherical image (paper section 4), as analysis outputs.

Focal points.  The node axes of the two ends of an edge are coplanar for a
conical mesh, so they meet in a point (or are parallel): the *focal point* of
the edge, a discrete centre of curvature.  Along one mesh polyline the axes
form a discrete developable surface whose edge of regression is the polyline
of these focal points.  The focal points of all edges of one family (rows or
columns) form a *focal mesh*; its quads, one per edge ``g`` of the other
family, lie in the beam plane of ``g`` (two points on each end axis of ``g``).

Spherical image.  The unit face normals around an interior vertex, in cyclic
order, form a quad on the unit sphere.  The mesh of these quads (dual
combinatorics: one quad per interior valence-4 vertex, one point per face)
is circular exactly when the mesh is conical: the normals lie on the circle
with spherical centre ``a_v`` and radius ``theta_v``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from optimize.mesh import Mesh


@dataclass(frozen=True)
class FocalMeshes:
    """Focal points per edge and the quads of the two focal meshes.

    points : (e, 3) float, focal point of each edge (midpoint of the closest
        points of the two axis lines); NaN where the axes are parallel
    radii : (e, 2) float, signed distance along ``a_v`` and ``a_w`` from the
        edge's ends to the focal point (model units); inf where parallel
    gap : (e,) float, distance between the two axis lines when skew (0 when
        they meet or are parallel, i.e. coplanar)
    family : (e,) int, 0 or 1 (rows / columns), -1 where the quads do not
        split the edges into two families (irregular vertices, n-gons)
    quads : (g, 4) int, edge indices of the focal quads ``[e1, e1', e2', e2]``
    quad_edge : (g,) int, the edge of the other family each quad belongs to
    quad_family : (g,) int, family of the quad's vertices (the focal mesh it is in)
    """

    points: np.ndarray
    radii: np.ndarray
    gap: np.ndarray
    family: np.ndarray
    quads: np.ndarray
    quad_edge: np.ndarray
    quad_family: np.ndarray

    def focal_mesh(self, family: int) -> tuple[np.ndarray, np.ndarray]:
        """Points ``(e, 3)`` (all edges, NaN at infinity) and quads ``(g, 4)`` of one focal mesh."""
        return self.points, self.quads[self.quad_family == family]


def axis_line_intersections(V: np.ndarray, axes: np.ndarray, edges: np.ndarray
                            ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Closest points of the axis lines ``v + s a_v`` and ``w + t a_w`` of every edge.

    Parameters: ``V, axes (n, 3)`` (unit axes), ``edges (e, 2)``.
    Returns ``points (e, 3)``, ``radii (e, 2) = (s, t)``, ``gap (e,)`` (the
    distance between skew lines); parallel axes give NaN points, infinite
    radii and ``gap = 0`` (parallel lines are coplanar).
    """
    v, w = edges[:, 0], edges[:, 1]
    a, b = axes[v], axes[w]
    r = V[w] - V[v]
    c = np.einsum("ij,ij->i", a, b)
    ar, br = np.einsum("ij,ij->i", a, r), np.einsum("ij,ij->i", b, r)
    axb = np.cross(a, b)
    D = np.einsum("ij,ij->i", axb, axb)
    par = D < 1e-24
    Ds = np.where(par, 1.0, D)
    s = np.where(par, np.inf, (ar - c * br) / Ds)
    t = np.where(par, np.inf, (c * ar - br) / Ds)
    gap = np.where(par, 0.0, np.abs(np.einsum("ij,ij->i", r, axb)) / np.sqrt(Ds))
    with np.errstate(invalid="ignore"):
        P = 0.5 * (V[v] + s[:, None] * a + V[w] + t[:, None] * b)
    P[par] = np.nan
    return P, np.stack([s, t], axis=1), gap


def edge_families(mesh: Mesh) -> np.ndarray:
    """(e,) int: split the edges into two families (0, 1) so that in every quad
    opposite edges share a family and neighbouring edges do not; ``-1`` on the
    edges where that is impossible (odd cycles around irregular vertices)."""
    t = mesh.topology
    ne = len(t.edges)
    quads = np.nonzero(t.face_sizes == 4)[0]
    c = t.offsets[quads][:, None] + np.arange(4)[None, :]
    E = t.corner_edge[c]  # (q, 4)
    same = np.concatenate([E[:, [0, 2]], E[:, [1, 3]]])
    _, strip = connected_components(
        sp.coo_matrix((np.ones(len(same)), (same[:, 0], same[:, 1])), shape=(ne, ne)), directed=False)
    ns = int(strip.max()) + 1
    diff = strip[np.concatenate([E[:, [0, 1]], E[:, [1, 2]]])]  # (2q, 2) strip pairs
    # doubled graph: strip x -> nodes x (colour 0) and x + ns (colour 1)
    i = np.concatenate([diff[:, 0], diff[:, 0] + ns])
    j = np.concatenate([diff[:, 1] + ns, diff[:, 1]])
    _, comp = connected_components(sp.coo_matrix((np.ones(len(i)), (i, j)), shape=(2 * ns, 2 * ns)),
                                   directed=False)
    c0, c1 = comp[:ns], comp[ns:]
    colour = np.where(c0 == c1, -1, (c0 > c1).astype(np.int64))
    return colour[strip]


def focal_meshes(mesh: Mesh, axes: np.ndarray) -> FocalMeshes:
    """Focal points of every edge and the focal quads across every interior quad-quad edge.

    ``axes (n, 3)``: unit node axes of ``mesh``.
    """
    t = mesh.topology
    points, radii, gap = axis_line_intersections(mesh.V, axes, t.edges)
    family = edge_families(mesh)
    h0, h1 = t.edge_corners[:, 0], t.edge_corners[:, 1]
    inner = (h1 >= 0)
    inner &= (t.face_sizes[t.corner_face[h0]] == 4) & (t.face_sizes[t.corner_face[np.maximum(h1, 0)]] == 4)
    g = np.nonzero(inner)[0]
    h, h2 = h0[g], h1[g]
    Q = np.stack([t.corner_edge[t.corner_prev[h]], t.corner_edge[t.corner_next[h]],
                  t.corner_edge[t.corner_prev[h2]], t.corner_edge[t.corner_next[h2]]], axis=1)
    return FocalMeshes(points=points, radii=radii, gap=gap, family=family, quads=Q,
                       quad_edge=g, quad_family=family[Q[:, 0]])


def spherical_image(mesh: Mesh, normals: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The spherical image of the face normals.

    Returns ``points (m, 3)`` (the unit normals), ``quads (p, 4)`` (face indices
    around each interior valence-4 vertex, cyclic order) and ``vertices (p,)``
    (the mesh vertex of each quad).
    """
    t = mesh.topology
    inner = t.interior_valence4
    return normals, t.star_faces[inner, :4], inner


def quad_circular_defect(P: np.ndarray) -> np.ndarray:
    """(q,) float: ``max(|phi1 + phi3 - pi|, |phi2 + phi4 - pi|)`` of quads ``P (q, 4, 3)``.

    NaN for degenerate quads (an edge shorter than 1e-12 of the longest one),
    e.g. the spherical image at a cylinder-like vertex where normals repeat.
    """
    u = np.roll(P, -1, axis=1) - P
    w = np.roll(P, 1, axis=1) - P
    phi = np.arctan2(np.linalg.norm(np.cross(u, w), axis=2), np.einsum("qkj,qkj->qk", u, w))
    d = np.maximum(np.abs(phi[:, 0] + phi[:, 2] - np.pi), np.abs(phi[:, 1] + phi[:, 3] - np.pi))
    length = np.linalg.norm(u, axis=2)
    degenerate = length.min(axis=1) <= 1e-12 * np.maximum(length.max(axis=1), 1e-300)
    return np.where(degenerate, np.nan, d)


def spherical_image_defect(mesh: Mesh, normals: np.ndarray) -> np.ndarray:
    """(p,) float: circular defect of the spherical-image quad of every interior valence-4 vertex."""
    P, quads, _ = spherical_image(mesh, normals)
    return quad_circular_defect(P[quads])
