"""Loads on the frame: the basic cases (EN 1991-style) and their combinations (EN 1990-style).

Units in: kN/m3 and kN/m2 (config); out: N and mm (N/mm line loads).  A panel's load goes to
the beams on its edges by tributary area (:func:`tributary_shares`: the panel, in its plane, split
into the regions nearest each edge, the straight skeleton of a convex polygon: a rectangle's short
edge takes the 45-degree triangle, its long edge the trapezoid; a triangle's edges take their share
by length), as a uniform line load on each beam (the total on each beam is exact; the triangular or
trapezoidal shape along it is not modelled: the mid-span moment of a triangle is WL/6 where a
uniform load gives WL/8); totals are exact, so the sum of the reactions is the sum of the loads.

- ``self_weight``: steel unit weight x section area, downward (``-up``), per beam;
- ``hubs``: the node parts (hubs, plates) of the CAD stage, their volume x steel unit weight, at the
  nodes (when the parts are given);
- ``glass``: glass unit weight x thickness x panel area, downward (``parts.glass_thickness`` is the
  weight of every ply and interlayer of the glass build-up);
- ``maintenance``: EN 1991-1-1 category H roofs, kN/m2 of plan (Table 6.10 recommends q_k 0.4);
  not combined with snow or wind (3.3.2(1));
- ``temperature_rise`` / ``temperature_fall``: a uniform temperature change +/- dT of every beam
  (strain alpha dT, steel alpha 12e-6/K, EN 1991-1-5 Table C.1): the members held at both ends push
  their nodes with E A alpha dT (``LoadCase.fixed_end`` takes that force back out of the members);
- ``finishes``: kN/m2 of panel area, downward;
- ``snow``: kN/m2 on the plan projection ``|A_f . up|``, downward;
- ``wind_pressure`` / ``wind_suction``: kN/m2 of panel area along the panel normal, toward the
  beams (pressure) or away from them (suction).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

KN_M3 = 1e-6   # kN/m3 -> N/mm3
KN_M2 = 1e-3   # kN/m2 -> N/mm2


@dataclass(frozen=True, eq=False)
class LoadCase:
    """One load case: ``nodal (n, 6)`` forces N and moments N mm, ``line (e, 3)`` global uniform
    line loads N/mm on the elements; ``fixed_end (e, 12)`` or None: local end forces of the members
    held at both ends (an imposed strain: temperature), added to the solved end forces (their
    equivalent nodal loads are in ``nodal``)."""

    name: str
    nodal: np.ndarray
    line: np.ndarray
    fixed_end: np.ndarray | None = None

    def total_force(self, lengths: np.ndarray) -> np.ndarray:
        """(3,) float resultant force, N, for element ``lengths (e,)``."""
        return self.nodal[:, :3].sum(axis=0) + (self.line * lengths[:, None]).sum(axis=0)

    def scaled(self, factor: float, name: str | None = None) -> "LoadCase":
        return LoadCase(name or self.name, self.nodal * factor, self.line * factor,
                        None if self.fixed_end is None else self.fixed_end * factor)


def combine(cases: dict[str, LoadCase], factors: dict[str, float], name: str) -> LoadCase:
    """``sum factor * case`` over the cases named in ``factors``."""
    first = next(iter(cases.values()))
    nodal, line = np.zeros_like(first.nodal), np.zeros_like(first.line)
    fixed = np.zeros((len(first.line), 12))
    for key, f in factors.items():
        nodal += f * cases[key].nodal
        line += f * cases[key].line
        if cases[key].fixed_end is not None:
            fixed += f * cases[key].fixed_end
    return LoadCase(name, nodal, line, fixed)


def panel_area_vectors(mesh) -> np.ndarray:
    """(m, 3) float vector areas (Newell, in corner order) of the faces of ``mesh``, mm2."""
    t = mesh.topology
    V = np.asarray(mesh.V)
    base = V[mesh.F[:, 0]][t.corner_face]  # relative to a corner of the face: no round-off far from the origin
    c = np.cross(V[t.corner_vertex] - base, V[t.corner_next_vertex] - base)
    out = np.zeros((mesh.n_faces, 3))
    np.add.at(out, t.corner_face, c)
    return 0.5 * out


def _clip(poly: np.ndarray, cnt: np.ndarray, a: np.ndarray, b: np.ndarray):
    """Convex polygons ``poly (m, K, 2)`` (``cnt (m,)`` vertices each) cut to ``a . p >= b``
    (``a (m, 2)``, ``b (m,)``; Sutherland-Hodgman, all polygons at once)."""
    m, K, _ = poly.shape
    k = np.arange(K)[None, :]
    valid = k < cnt[:, None]
    nxt = np.where(k + 1 < cnt[:, None], k + 1, 0)
    q = np.take_along_axis(poly, nxt[:, :, None], axis=1)
    s0 = np.einsum("mkd,md->mk", poly, a) - b[:, None]
    s1 = np.take_along_axis(s0, nxt, axis=1)
    keep = valid & (s0 >= 0)
    cross = valid & (((s0 >= 0) & (s1 < 0)) | ((s0 < 0) & (s1 >= 0)))
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(cross, s0 / (s0 - s1), 0.0)
    inter = poly + t[:, :, None] * (q - poly)
    out = np.stack([poly, inter], axis=2).reshape(m, 2 * K, 2)
    mask = np.stack([keep, cross], axis=2).reshape(m, 2 * K)
    order = np.argsort(~mask, axis=1, kind="stable")
    out = np.take_along_axis(out, order[:, :, None], axis=1)
    cnt = mask.sum(axis=1)
    top = max(int(cnt.max(initial=0)), 1)
    return out[:, :top], cnt


def _area(poly: np.ndarray, cnt: np.ndarray) -> np.ndarray:
    K = poly.shape[1]
    k = np.arange(K)[None, :]
    nxt = np.where(k + 1 < cnt[:, None], k + 1, 0)
    q = np.take_along_axis(poly, nxt[:, :, None], axis=1)
    c = poly[:, :, 0] * q[:, :, 1] - poly[:, :, 1] * q[:, :, 0]
    return 0.5 * np.where(k < cnt[:, None], c, 0.0).sum(axis=1)


def tributary_shares(mesh) -> np.ndarray:
    """(c,) float the share of its face's area each corner's edge (corner to next corner) carries: the
    region of the face (in its Newell plane) nearer that edge's line than any other's, the straight
    skeleton of a convex face (each region clipped out by half-planes ``d_i <= d_j``); shares of a
    face sum to 1."""
    t = mesh.topology
    V = np.asarray(mesh.V, dtype=float)
    m = mesh.n_faces
    sizes = np.asarray(t.face_sizes)
    k = int(sizes.max(initial=0))
    j = np.arange(k)[None, :]
    corner = np.asarray(t.offsets[:-1])[:, None] + np.minimum(j, sizes[:, None] - 1)
    P = V[np.asarray(t.corner_vertex)[corner]]                        # (m, k, 3), the last corner repeated
    nrm = panel_area_vectors(mesh)
    nrm = nrm / np.maximum(np.linalg.norm(nrm, axis=1, keepdims=True), 1e-300)
    u = P[:, 1] - P[:, 0]
    u /= np.maximum(np.linalg.norm(u, axis=1, keepdims=True), 1e-300)
    v = np.cross(nrm, u)
    rel = P - P[:, :1]
    Q = np.stack([np.einsum("mkd,md->mk", rel, u), np.einsum("mkd,md->mk", rel, v)], axis=2)   # CCW in 2D
    nxt = np.where(j + 1 < sizes[:, None], j + 1, 0)
    d = np.take_along_axis(Q, nxt[:, :, None], axis=1) - Q
    inward = np.stack([-d[..., 1], d[..., 0]], axis=2)
    inward /= np.maximum(np.linalg.norm(inward, axis=2, keepdims=True), 1e-300)
    off = np.einsum("mkd,mkd->mk", inward, Q)                          # d_i(p) = inward_i . p - off_i
    area = np.zeros((m, k))
    for i in range(k):
        poly, cnt = Q.copy(), sizes.copy()
        for jj in range(k):
            if jj == i:
                continue
            live = (jj < sizes) & (i < sizes)
            a = np.where(live[:, None], inward[:, jj] - inward[:, i], 0.0)
            b = np.where(live, off[:, jj] - off[:, i], -1.0)          # dead: 0 >= -1 keeps everything
            poly, cnt = _clip(poly, cnt, a, b)
        area[:, i] = np.where(i < sizes, _area(poly, cnt), 0.0)
    total = area.sum(axis=1, keepdims=True)
    share = np.where(total > 0, area / np.where(total > 0, total, 1.0), 1.0 / np.maximum(sizes[:, None], 1))
    local = np.arange(len(t.corner_face)) - np.asarray(t.offsets)[t.corner_face]
    return share[t.corner_face, local]


def panel_forces_to_beams(mesh, forces: np.ndarray, n_edges: int) -> np.ndarray:
    """(e, 3) float total force on each beam from the panel ``forces (m, 3)`` (N), split over each
    panel's edges by tributary area (:func:`tributary_shares`)."""
    t = mesh.topology
    share = tributary_shares(mesh)
    out = np.zeros((n_edges, 3))
    np.add.at(out, t.corner_edge, forces[t.corner_face] * share[:, None])
    return out


ALPHA_STEEL = 12e-6
"""Coefficient of thermal expansion of steel, 1/K (EN 1991-1-5 Table C.1)."""


def node_weights(parts, n_nodes: int, unit_weight: float) -> np.ndarray:
    """(n,) float weight (N) of the node parts (hubs, plates) of ``parts`` at each mesh vertex: their
    volumes (mm3) x ``unit_weight`` (kN/m3)."""
    out = np.zeros(n_nodes)
    if parts is None:
        return out
    for g in parts.of_kind("node"):
        np.add.at(out, np.asarray(g.element, dtype=np.int64), np.asarray(g.volume_mm3) * unit_weight * KN_M3)
    return out


def thermal_case(frame, dT: float, name: str) -> LoadCase:
    """A uniform temperature change ``dT`` (K) of every member: nodal loads ``E A alpha dT`` along each
    member, pushing its nodes apart, and the held members' end forces (compression for a rise)."""
    axes = frame.local_axes()
    P = frame.E * frame.prop("A") * ALPHA_STEEL * dT                  # N, + pushes the nodes apart
    nodal = np.zeros((frame.n_nodes, 6))
    np.add.at(nodal[:, :3], frame.elements[:, 0], -P[:, None] * axes[:, 0])
    np.add.at(nodal[:, :3], frame.elements[:, 1], P[:, None] * axes[:, 0])
    fixed = np.zeros((frame.n_elements, 12))
    fixed[:, 0], fixed[:, 6] = P, -P                                 # N = -P on the held member
    return LoadCase(name, nodal, np.zeros((frame.n_elements, 3)), fixed)


def basic_cases(structure, frame, loads, glass_thickness: float, up=(0.0, 0.0, 1.0), parts=None) -> dict[str, LoadCase]:
    """The basic load cases ``{name: LoadCase}`` (see the module docstring) of the frame
    ``frame`` built on ``structure`` (an OffsetStructure); ``loads`` a LoadsOption (kN/m3, kN/m2),
    ``glass_thickness`` mm; ``parts`` the CAD stage's Parts (the hubs' weight) or None."""
    mesh = structure.mesh
    u = np.asarray(up, dtype=float) / np.linalg.norm(up)
    L = frame.lengths()
    n, e = frame.n_nodes, frame.n_elements
    Avec = panel_area_vectors(mesh)
    area = np.linalg.norm(Avec, axis=1)
    normal = np.asarray(structure.normals, dtype=float)  # unit, flipped as the offset stage used them
    d0, d1 = structure.beam_span
    toward = np.sign(d1 - d0) or -1.0                     # beams lie on this side of the glass
    per_area = {
        "glass": -u[None, :] * (loads.glass_unit_weight * KN_M3 * glass_thickness * area)[:, None],
        "finishes": -u[None, :] * (loads.finishes * KN_M2 * area)[:, None],
        "snow": -u[None, :] * (loads.snow * KN_M2 * np.abs(Avec @ u))[:, None],
        "wind_pressure": toward * normal * (loads.wind_pressure * KN_M2 * area)[:, None],
        "wind_suction": -toward * normal * (loads.wind_suction * KN_M2 * area)[:, None],
        "maintenance": -u[None, :] * (loads.maintenance * KN_M2 * np.abs(Avec @ u))[:, None],
    }
    zeros = np.zeros((n, 6))
    cases = {"self_weight": LoadCase("self_weight", zeros,
                                     -u[None, :] * (loads.steel_unit_weight * KN_M3 * frame.prop("A"))[:, None])}
    hubs = np.zeros((n, 6))
    hubs[:, :3] = -u[None, :] * node_weights(parts, n, loads.steel_unit_weight)[:, None]
    cases["hubs"] = LoadCase("hubs", hubs, np.zeros((e, 3)))
    for name, F in per_area.items():
        cases[name] = LoadCase(name, zeros, panel_forces_to_beams(mesh, F, e) / L[:, None])
    cases["temperature_rise"] = thermal_case(frame, loads.temperature, "temperature_rise")
    cases["temperature_fall"] = thermal_case(frame, -loads.temperature, "temperature_fall")
    return cases
