"""Nodes: a polygonal cylinder on every node axis (optional).

The node of vertex ``v`` is a regular ``node_sides``-gon prism of circumradius
``node_radius`` around the axis line, between the first and the last layer,
with both caps normal to the axis and recessed by ``r tan(theta_max)`` (the
largest angle between the axis and a face normal around ``v``), so that no
cap reaches through a face plane into the glass.  The beams stop at least
``node_radius`` from the axis, so they never enter a node.
"""
from __future__ import annotations

import numpy as np

from .beams import _node_frames
from .geometry import dot, unit
from .panels import prism_faces


def node_solids(structure, P0: np.ndarray, P1: np.ndarray, radius: float, sides: int) -> dict:
    """Vertices ``(n, 2 K, 3)``, outward normals ``(n, K + 2, 3)``, ``faces``, ``theta_max (n,)``.

    Same vertex and face layout as a panel (:func:`fabricate.cad.panels.prism_faces`):
    lower ring, upper ring (along the axis), caps first.  P0, P1 : (n, 3) vertex
    positions at the first and last layer.
    """
    mesh = structure.mesh
    topo = mesh.topology
    a = unit(np.asarray(structure.axes, dtype=float))
    N = unit(np.asarray(structure.normals, dtype=float))
    star = topo.star_faces                                  # (n, s), -1 padded
    cos_f = np.where(star >= 0, dot(N[np.maximum(star, 0)], a[:, None, :]), 1.0)
    theta = np.arccos(np.clip(cos_f.min(axis=1), -1.0, 1.0))
    recess = radius * np.tan(np.minimum(theta, np.radians(89.0)))
    z1 = dot(P1 - P0, a)                                    # signed axial length to the last layer
    direction = np.sign(z1)
    za = direction * recess
    zb = z1 - direction * recess
    z_lo, z_hi = np.minimum(za, zb), np.maximum(za, zb)
    fx, fy = _node_frames(a)
    phi = 2 * np.pi * np.arange(sides) / sides
    ring = radius * (np.cos(phi)[None, :, None] * fx[:, None, :] + np.sin(phi)[None, :, None] * fy[:, None, :])
    lo = P0[:, None, :] + z_lo[:, None, None] * a[:, None, :] + ring
    hi = P0[:, None, :] + z_hi[:, None, None] * a[:, None, :] + ring
    mid = phi + np.pi / sides
    side_n = np.cos(mid)[None, :, None] * fx[:, None, :] + np.sin(mid)[None, :, None] * fy[:, None, :]
    normals = np.concatenate([-a[:, None, :], a[:, None, :], side_n], axis=1)
    return {"vertices": np.concatenate([lo, hi], axis=1), "normals": normals,
            "faces": prism_faces(sides), "theta_max": theta, "length": z_hi - z_lo}


FILLER_DEG = 90.0
"""The largest angle (deg) between two neighbouring flats of a faceted node: a wider gap between two
beams (a boundary node) gets flats without a beam in it, so the node stays a closed, compact polygon."""


def flat_layout(structure, P0: np.ndarray, P1: np.ndarray, radius: float, half_width: float,
                ridge_normals: np.ndarray | None = None) -> dict:
    """Where the flats of every faceted node lie: one flat square to each beam (the beam's saw-cut end
    rests on it) and flats without a beam in gaps wider than :data:`FILLER_DEG`.

    Seen along the node axis every flat is tangent to a circle of radius ``setback`` (per node): the
    hub radius, or more where two flats are so close in angle that beams ``half_width`` wide (half the
    wider of web and flanges) would pass their common corner: ``half_width / tan(gap / 2)``.
    Returns ``setback (n,)`` mm, ``rings`` a list per node of ``(azimuth unit (3,), beam end or -1)``
    in counter-clockwise order about ``up (n, 3)`` (unit, from the last layer to the first), and ``up``.

    ridge_normals : ``(e, 3)`` the normal of each beam's top flange plane (``T0+``; a boundary beam's
    two are the same: its one face's plane continued).  Between two boundary beams (a gap no face
    spans) the node's top continues each beam's plane up to their common line, where two flats meet
    in a corner (``outer (n,)``: that corner's azimuth, or nan).
    """
    E = np.asarray(structure.edges)
    Q = np.asarray(structure.beam_quads, dtype=float)
    up = unit(P0 - P1)
    fx, fy = _node_frames(up)
    n = len(P0)
    ends = [[] for _ in range(n)]                             # (angle, edge, end)
    d = np.stack([Q[:, 1] - Q[:, 0], Q[:, 0] - Q[:, 1]], axis=1)   # from each end toward the other
    for end in (0, 1):
        v = E[:, end]
        dv = d[:, end] - dot(d[:, end], up[v])[:, None] * up[v]
        ang = np.arctan2(dot(dv, fy[v]), dot(dv, fx[v]))
        for e, (vv, a) in enumerate(zip(v.tolist(), ang.tolist())):
            ends[vv].append((a, e, end))
    setback = np.full(n, float(radius))
    rings = []
    step = np.radians(FILLER_DEG)
    ef = [set(f for f in row if f >= 0) for row in structure.mesh.topology.edge_faces.tolist()]

    def fill(a0, a1):                   # flats strictly between azimuths a0 < a1, sub-gaps <= FILLER_DEG
        k = int(np.ceil((a1 - a0) / step - 1e-9))
        return [(a0 + (a1 - a0) * i / k, -1) for i in range(1, k)]

    for v in range(n):
        row = sorted(ends[v])
        ring, tags = [], []               # tags: the plane of the corner after each flat (0 gap, 1 / 2 a beam's)
        for j, (a, e, end) in enumerate(row):
            ring.append((a, 2 * e + end))
            e1 = row[(j + 1) % len(row)][1]
            nxt = row[(j + 1) % len(row)][0] + (2 * np.pi if j + 1 >= len(row) else 0.0)
            gap = nxt - a if len(row) > 1 else 2 * np.pi
            psi = np.nan
            if ridge_normals is not None and not (ef[e] & ef[e1]) and e1 != e:   # a gap outside the mesh
                L = np.cross(ridge_normals[e], ridge_normals[e1])
                if np.linalg.norm(L) > 1e-9:
                    for sgn in (1.0, -1.0):
                        p = np.arctan2(dot(sgn * L, fy[v]), dot(sgn * L, fx[v]))
                        p = a + (p - a) % (2 * np.pi)
                        if a + 0.05 < p < nxt - 0.05:
                            psi = p
            if np.isnan(psi):
                tags += [0] * (1 + len(fill(a, nxt)))
                ring += fill(a, nxt)
                continue
            dl = min(np.pi / 4, 0.5 * (psi - a), 0.5 * (nxt - psi))    # two flats meeting in a corner at psi
            more = fill(a, psi - dl) + [(psi - dl, -1)] + fill(psi - dl, psi + dl) + [(psi + dl, -1)] \
                + fill(psi + dl, nxt)
            ring += more
            az = [a] + [x[0] for x in more] + [nxt]
            tags += [1 if 0.5 * (az[i] + az[i + 1]) < psi + 1e-9 else 2 for i in range(len(az) - 1)]
        angles = np.array([r[0] for r in ring])
        beam = np.array([r[1] for r in ring])
        gaps = np.diff(np.r_[angles, angles[0] + 2 * np.pi])
        both = np.minimum(gaps, np.roll(gaps, 1))[beam >= 0]           # each beam flat: its nearer corner
        if len(both):
            setback[v] = max(setback[v], float((half_width / np.tan(np.minimum(both, np.pi - 1e-9) / 2)).max()))
        rings.append((angles, beam, np.array(tags)))
    return {"setback": setback, "rings": rings, "up": up, "fx": fx, "fy": fy}


def _gap_planes(apex, r0, r1, up):
    """Normals ``(m, 3)`` of the planes through a node's apex holding two neighbouring ridge lines
    (directions ``r0``, ``r1``): the glass plane between two beams.  Ridges that are nearly opposite
    (a boundary gap) span the plane through ``r0`` level across it."""
    c = np.cross(r0, r1)
    s = np.linalg.norm(c, axis=1) / np.maximum(np.linalg.norm(r0, axis=1) * np.linalg.norm(r1, axis=1), 1e-300)
    level = np.cross(r0, np.cross(up, r0))
    n = np.where((s > 0.2)[:, None], c, level)
    n = unit(n)
    return np.where((dot(n, up) < 0)[:, None], -n, n)


def faceted_nodes(structure, P0: np.ndarray, P1: np.ndarray, layout: dict, wall: float | None,
                  ridge_normals: np.ndarray | None = None) -> list[dict]:
    """Faceted hubs: the polygon of :func:`flat_layout` between the glass planes and the planes of the
    last layer, so every beam end (web and flanges, top to bottom) rests on a flat, and the top is the
    glass planes around the node (the panels bear on it as on the beams' top flanges).

    Seen along the axis, the ring of a node is: at each beam flat its ridge point (where the beam's
    ridge lines meet the flat), then the corner to the next flat.  Every ring point stands at the height
    of the glass plane of its gap (the plane through the node's first-layer point that holds the two
    beams' ridge lines; the mesh face's plane for a conical mesh) and at the bottom on the same plane of
    the last layer, so the flats are vertical planar quads and the top and bottom are planar too.

    wall : None for a solid hub (one solid: ring, apexes on the axis, a fan of triangles top and bottom),
    else a tube of that wall (flats ``wall`` thick; :func:`fabricate.cad.hubs.tube_faces` layout).
    ridge_normals : ``(e, 2, 3)`` each beam's flange planes at the first and last layer (``T0+``,
    ``T1+``): beside a gap outside the mesh the node's top and bottom continue them (see
    :func:`flat_layout`).
    Returns one dict per ring size ``m``: ``index (q,)`` nodes, ``vertices``, ``normals``, ``faces``,
    ``inner`` (tube: the inner ring heights ``(q, 2, m)``), ``m``.
    """
    Q = np.asarray(structure.beam_quads, dtype=float)
    E = np.asarray(structure.edges)
    up, fx, fy, S = layout["up"], layout["fx"], layout["fy"], layout["setback"]
    rows = []   # per node: plan offsets (m, 2) outer, ridge / gap assignment
    for v, (ang, beam, tags) in enumerate(layout["rings"]):
        k = len(ang)
        nxt = np.roll(ang, -1)
        nxt = np.where(np.arange(k) == k - 1, nxt + 2 * np.pi, nxt)
        pts, gap_of, is_ridge, flat, tag = [], [], [], [], []
        g = -1
        for j in range(k):
            if beam[j] >= 0:
                g += 1
                pts.append((ang[j], 0.0))        # the ridge point: on the flat at the beam's azimuth
                gap_of.append(g)
                is_ridge.append(int(beam[j]))
                flat.append(j)
                tag.append(0)
            pts.append((0.5 * (ang[j] + nxt[j]), 0.5 * (nxt[j] - ang[j])))  # corner to the next flat
            gap_of.append(g)
            is_ridge.append(-1)
            flat.append(j)
            tag.append(int(tags[j]))
        rows.append((np.array(pts), np.array(gap_of), np.array(is_ridge), np.array(tag)))
    out = []
    sizes = np.array([len(r[0]) for r in rows])
    for m in np.unique(sizes):
        idx = np.flatnonzero(sizes == m)
        q = len(idx)
        pts = np.stack([rows[v][0] for v in idx])                     # (q, m, 2) azimuth, half gap
        ridge = np.stack([rows[v][2] for v in idx])                    # (q, m) beam end (2 e + end) or -1
        gap = np.stack([rows[v][1] for v in idx])
        tag = np.stack([rows[v][3] for v in idx])
        # the ridge ends of every gap: the ridge before it (its own index) and after it
        nbeams = (ridge >= 0).sum(axis=1)
        gap = np.where(gap < 0, nbeams[:, None] - 1, gap)             # corners before the first beam: the last gap
        ridge_ends = np.full((q, m), -1)
        order = np.argsort(np.where(ridge >= 0, 0, 1), axis=1, kind="stable")
        ridge_ends = np.take_along_axis(ridge, order, axis=1)          # beam ends in ring order, then -1
        b0 = np.take_along_axis(ridge_ends, gap, axis=1)
        b1 = np.take_along_axis(ridge_ends, (gap + 1) % np.maximum(nbeams, 1)[:, None], axis=1)

        def ridge_dir(be, layer):                                      # (q, m, 3): from the node along the beam
            e, end = be // 2, be % 2
            a_i, b_i = (0, 1) if layer == 0 else (3, 2)
            here = np.where(end[..., None] == 0, Q[e, a_i], Q[e, b_i])
            there = np.where(end[..., None] == 0, Q[e, b_i], Q[e, a_i])
            return there - here

        a = up[idx][:, None, :]
        az, half = pts[..., 0], pts[..., 1]
        d = np.cos(az)[..., None] * fx[idx][:, None, :] + np.sin(az)[..., None] * fy[idx][:, None, :]
        rings = []
        for s_off in ([0.0] if wall is None else [0.0, float(wall)]):
            s = (S[idx] - s_off)[:, None] / np.cos(half)               # corners lie further out
            plan = s[..., None] * d
            layers = []
            for layer, apex in ((0, P0[idx]), (1, P1[idx])):
                nrm = _gap_planes(apex, ridge_dir(b0, layer).reshape(-1, 3), ridge_dir(b1, layer).reshape(-1, 3),
                                  np.repeat(up[idx], m, axis=0)).reshape(q, m, 3)
                if ridge_normals is not None:                          # beside a gap outside the mesh
                    for t, be in ((1, b0), (2, b1)):
                        nrm = np.where((tag == t)[..., None], ridge_normals[be // 2, layer], nrm)
                # a ridge point lies on its ridge line (in both gap planes); a corner on its gap's plane
                z = -dot(nrm, plan) / dot(nrm, a)
                rd = ridge_dir(np.maximum(ridge, 0), layer)
                hor = np.linalg.norm(rd - dot(rd, a)[..., None] * a, axis=-1)
                zr = s * dot(rd, a) / np.maximum(hor, 1e-300)
                z = np.where(ridge >= 0, zr, z)
                layers.append(apex[:, None, :] + plan + z[..., None] * a)
            rings.append(layers)
        (top, bot) = rings[0]
        if wall is None:
            V = np.concatenate([bot, top, P1[idx][:, None, :], P0[idx][:, None, :]], axis=1)
            faces = solid_faces(int(m))
        else:
            itop, ibot = rings[1]
            V = np.concatenate([bot, top, ibot, itop], axis=1)
            from .hubs import tube_faces
            faces = tube_faces(int(m))
        normals = face_normals(V, faces)
        out.append({"index": idx, "vertices": V, "normals": normals, "faces": faces, "m": int(m),
                    "height": dot(top - bot, a).min(axis=1), "setback": S[idx],
                    "apex": np.stack([P0[idx], P1[idx]], axis=1), "ridge": ridge})
    return out


def solid_faces(m: int) -> tuple[tuple[int, ...], ...]:
    """A faceted solid hub: ring ``0..m-1`` at the bottom, ``m..2m-1`` on top, apex bottom ``2m`` and top
    ``2m+1`` (on the axis); ``m`` side quads, then ``m`` top and ``m`` bottom triangles (outward)."""
    sides = tuple((j, (j + 1) % m, m + (j + 1) % m, m + j) for j in range(m))
    top = tuple((2 * m + 1, m + j, m + (j + 1) % m) for j in range(m))
    bottom = tuple((2 * m, (j + 1) % m, j) for j in range(m))
    return sides + top + bottom


def face_normals(V: np.ndarray, faces) -> np.ndarray:
    """(p, f, 3) unit normals of planar faces (Newell's method: exact for planar polygons)."""
    out = np.empty((len(V), len(faces), 3))
    for i, f in enumerate(faces):
        P = V[:, list(f)]
        Pn = np.roll(P, -1, axis=1)
        out[:, i] = unit(np.cross(P, Pn).sum(axis=1))
    return out
