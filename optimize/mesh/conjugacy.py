"""How far the mesh lines of a quad mesh are from a conjugate net (and from the principal net).

A PQ mesh near a smooth surface follows a conjugate net of it (Liu et al.
2006, section 3): the mixed derivative ``f_uv`` of the net is tangent,
``II(f_u, f_v) = 0``.  A conical or circular mesh follows the principal net
(conjugate and orthogonal).  An input whose mesh lines are far from such a
net has no fold-free PQ mesh near it; the way forward is to remesh along
principal directions (:mod:`optimize.remesh.quads`).

At every interior valence-4 vertex ``v`` with neighbours ``n0..n3`` in cyclic
order (``n0, n2`` on one mesh line, ``n1, n3`` on the other) and the
opposite corners ``d01, d12, d23, d30`` of its four faces, central
differences give ``f_u = (n0 - n2) / 2``, ``f_v = (n1 - n3) / 2``,
``f_uu = n0 - 2 v + n2``, ``f_vv = n1 - 2 v + n3``,
``f_uv = (d01 - d12 + d23 - d30) / 4`` and the normal ``n = f_u x f_v / |..|``.
In the unit directions of the lines the second fundamental form is
``e = n.f_uu / |f_u|^2``, ``g = n.f_vv / |f_v|^2``, ``f = n.f_uv / (|f_u||f_v|)``.

- conjugacy defect ``sqrt(2) |f| / sqrt(e^2 + 2 f^2 + g^2)`` in ``[0, 1]``:
  0 for a conjugate net, 1 for an asymptotic one (the rulings of a hypar);
- principal angle: the angle between the mesh lines and the nearest
  principal direction of ``(I, II)`` (degrees; 0 for a principal net).

Both are averaged with weight ``sqrt(e^2 + 2 f^2 + g^2)`` (the curvature
magnitude; flat regions have no preferred net and say nothing).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..mesh import Mesh

FAR = 0.3  # conjugacy defect (weighted mean) above which remeshing is the advice / the 'auto' choice
FAR_PRINCIPAL = 15.0  # degrees off the principal directions, for conical / circular


@dataclass
class NetDefect:
    """Per-vertex figures at ``vertices (p,)`` and their curvature-weighted means."""

    vertices: np.ndarray
    conjugacy: np.ndarray  # (p,) in [0, 1]
    principal_angle: np.ndarray  # (p,) degrees
    weight: np.ndarray  # (p,)
    mean_conjugacy: float
    mean_principal_angle: float

    def figure(self, target: str) -> float:
        """The one figure that matters for ``target``: conjugacy (pq), principal angle (else)."""
        return self.mean_conjugacy if target == "pq" else self.mean_principal_angle

    def far(self, target: str) -> bool:
        """True when the mesh lines are far from the net ``target`` needs."""
        return self.figure(target) > (FAR if target == "pq" else FAR_PRINCIPAL)

    def line(self, target: str) -> str:
        """One sentence with the figure, for reports."""
        n = len(self.vertices)
        if not n or not self.weight.sum() > 0:
            return "mesh lines vs conjugate net: not measured (no curved interior valence-4 vertex)"
        if target == "pq":
            text = (f"mesh lines vs conjugate net: defect {self.mean_conjugacy:.2f} (0 conjugate, "
                    f"1 asymptotic; {n} vertices, curvature-weighted)")
        else:
            text = (f"mesh lines vs principal directions: {self.mean_principal_angle:.1f} deg off "
                    f"(curvature-weighted, {n} vertices)")
        return text + ("; far: no fold-free mesh may be near, remeshing along principal directions "
                       "is the way forward" if self.far(target) else "")


def net_defect(mesh: Mesh, V: np.ndarray | None = None) -> NetDefect:
    """:class:`NetDefect` of ``mesh`` at positions ``V (n, 3)`` (default ``mesh.V``)."""
    V = mesh.V if V is None else V
    t = mesh.topology
    cv = t.interior_valence4
    C = t.star_corners[cv, :4]  # the corner of each star face at v, cyclic order
    nb = t.corner_next_vertex[C]  # (p, 4): the neighbour after v in each face
    opp = _opposite(mesh, C)
    P = V[cv]
    N0, N1, N2, N3 = (V[nb[:, k]] for k in range(4))
    D = V[opp]
    fu, fv = 0.5 * (N0 - N2), 0.5 * (N1 - N3)
    fuu, fvv = N0 - 2 * P + N2, N1 - 2 * P + N3
    fuv = 0.25 * (D[:, 0] - D[:, 1] + D[:, 2] - D[:, 3])
    n = np.cross(fu, fv)
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
    lu, lv = np.linalg.norm(fu, axis=1), np.linalg.norm(fv, axis=1)
    lu, lv = np.maximum(lu, 1e-300), np.maximum(lv, 1e-300)
    e = np.einsum("ij,ij->i", n, fuu) / lu ** 2
    g = np.einsum("ij,ij->i", n, fvv) / lv ** 2
    f = np.einsum("ij,ij->i", n, fuv) / (lu * lv)
    w = np.sqrt(e ** 2 + 2 * f ** 2 + g ** 2)
    conj = np.sqrt(2.0) * np.abs(f) / np.maximum(w, 1e-300)
    ang = _principal_angle(fu / lu[:, None], fv / lv[:, None], e, f, g)
    tw = w.sum()
    mean = lambda a: float((a * w).sum() / tw) if tw > 0 else 0.0  # noqa: E731
    return NetDefect(cv, conj, ang, w, mean(conj), mean(ang))


def _opposite(mesh: Mesh, C: np.ndarray) -> np.ndarray:
    """(p, 4) the vertex opposite the corner ``C`` in its (quad) face."""
    t = mesh.topology
    F = mesh.F[t.corner_face[C]]  # (p, 4, k)
    local = C - t.offsets[t.corner_face[C]]
    size = t.face_sizes[t.corner_face[C]]
    return np.take_along_axis(F, ((local + 2) % size)[..., None], axis=2)[..., 0]


def _principal_angle(tu, tv, e, f, g) -> np.ndarray:
    """(p,) degrees between the line ``tu`` and the nearest principal direction.

    In the basis ``(tu, tv)`` (unit, not orthogonal, ``c = tu . tv``) the first
    form is ``[[1, c], [c, 1]]`` and the second ``[[e, f], [f, g]]``; the principal
    directions ``x`` solve ``II x = k I x``.  Their angle to ``tu`` (and to ``tv``,
    whichever line is nearer: the worse of the two lines is reported)."""
    c = np.einsum("ij,ij->i", tu, tv)
    # principal directions in the tangent plane: with an orthonormal frame (tu, w),
    # w = (tv - c tu) / s, s = sqrt(1 - c^2): tv = c tu + s w
    s = np.sqrt(np.maximum(1 - c ** 2, 1e-300))
    # II in the orthonormal frame: II(tu,tu) = e, II(tu,w) = (f - c e) / s,
    # II(w,w) = (g - 2 c f + c^2 e) / s^2
    a, b, d = e, (f - c * e) / s, (g - 2 * c * f + c ** 2 * e) / s ** 2
    phi = 0.5 * np.arctan2(2 * b, a - d)  # a principal direction's angle from tu
    off_u = np.abs(((phi + np.pi / 4) % (np.pi / 2)) - np.pi / 4)  # to the nearest of the two (90 deg apart)
    psi = np.arctan2(s, c)  # tv's angle from tu
    off_v = np.abs(((phi - psi + np.pi / 4) % (np.pi / 2)) - np.pi / 4)
    return np.degrees(np.maximum(off_u, off_v))


def record_net(result, mesh: Mesh, target: str) -> None:
    """``result.defects["net"]``: :func:`net_defect` of the input ``mesh`` for ``target``
    (``conjugacy``, ``principal_angle_deg``, ``far``, the report ``line``); none for ``strip``."""
    if target not in ("pq", "conical", "circular"):
        return
    net = net_defect(mesh)
    result.defects["net"] = {"conjugacy": net.mean_conjugacy, "principal_angle_deg": net.mean_principal_angle,
                             "far": bool(net.far(target)), "line": net.line(target)}
