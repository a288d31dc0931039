"""The 3D scene of report.html, as :class:`fabricate.report.glb.GlbMesh` primitives (mm, z up):
the design coloured by planarity and its edges, the glass, beam and node solids of the CAD
stage (or the beam quads of the offset stage), and the other offset layers as wireframes."""
from __future__ import annotations

import numpy as np

from optimize.mesh import Mesh

from .glb import GlbMesh


def face_triangles(mesh: Mesh) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Unshared corners and fan triangles, so that every face has its own flat colour.

    Returns ``P (c, 3)`` corner positions, ``T (t, 3)`` triangles into ``P`` and
    ``face_of_corner (c,)``.
    """
    sizes = mesh.face_sizes
    P, T, owner, base = [], [], [], 0
    for k in np.unique(sizes):  # one gather per face size
        idx = np.nonzero(sizes == k)[0]
        corners = mesh.V[mesh.F[idx, :k]].reshape(-1, 3)
        first = base + k * np.arange(len(idx))[:, None]
        fan = np.stack([np.zeros(k - 2, int), np.arange(1, k - 1), np.arange(2, k)], axis=1)
        T.append((first[:, None, :] + fan[None, :, :]).reshape(-1, 3))
        P.append(corners)
        owner.append(np.repeat(idx, k))
        base += len(corners)
    return np.concatenate(P), np.concatenate(T), np.concatenate(owner)


def defect_colors(values: np.ndarray, tolerance: float | None) -> np.ndarray:
    """(k, 4) RGBA of ``values`` on the log colour scale of the pictures."""
    from matplotlib import colormaps

    from .pictures import _lognorm

    norm, v = _lognorm(values if len(values) else np.array([0.0]), tolerance)
    return colormaps["viridis"](norm(v))[: len(values)]


KIND_STYLE = {"panel": ("glass panels", (0.55, 0.78, 0.90, 0.45), 0.0, 0.1),
              "beam": ("steel beams", (0.45, 0.47, 0.50, 1.0), 0.7, 0.4),
              "node": ("nodes", (0.80, 0.45, 0.15, 1.0), 0.7, 0.4)}


FAILED_STYLE = (0.90, 0.10, 0.10, 1.0)
"""The colour of the parts a failed check or measure names (their own primitive, a toggle of the view)."""


def _solids(groups, select) -> tuple[list, list]:
    """Corner positions and fan triangles of the solids ``select(group)`` picks ((p,) bool per group)."""
    P, T, base = [], [], 0
    for g in groups:
        keep = select(g)
        if not keep.any():
            continue
        V = g.vertices[keep]
        p, nv = V.shape[:2]
        fan = np.array([(f[0], f[j], f[j + 1]) for f in g.faces for j in range(1, len(f) - 1)])
        T.append((fan[None, :, :] + nv * np.arange(p)[:, None, None]).reshape(-1, 3) + base)
        P.append(V.reshape(-1, 3))
        base += p * nv
    return P, T


def part_solids(parts, highlight=frozenset()) -> list[GlbMesh]:
    """One primitive per kind of part: every solid of every group, fan-triangulated faces; the parts
    whose ids are in ``highlight`` (a failed check's or measure's) drawn apart, in red, as one
    primitive named by their ids."""
    out = []
    marked = {id(g): np.array([i in highlight for i in g.ids], dtype=bool) for g in parts.groups}
    for kind, (name, colour, metallic, rough) in KIND_STYLE.items():
        P, T = _solids(parts.of_kind(kind), lambda g: ~marked[id(g)])
        if P:
            out.append(GlbMesh(name, np.concatenate(P), np.concatenate(T), color=colour, metallic=metallic,
                               roughness=rough))
    P, T = _solids(parts.groups, lambda g: marked[id(g)])
    if P:
        ids = sorted({i for g in parts.groups for i, m in zip(g.ids, marked[id(g)]) if m})
        label = ", ".join(ids[:8]) + (f" and {len(ids) - 8} more" if len(ids) > 8 else "")
        out.append(GlbMesh(f"failed parts ({label})", np.concatenate(P), np.concatenate(T), color=FAILED_STYLE,
                           metallic=0.0, roughness=0.5))
    return out


def build_scene(mesh: Mesh, planarity: np.ndarray, *, tolerance: float | None = None,
                structure=None, parts=None, highlight=frozenset()) -> list[GlbMesh]:
    """Primitives for the viewer.

    planarity : (m,) per-face planarity (colours the faces).
    structure : an ``OffsetStructure`` (beams and layers) or None.
    parts : ``fabricate.cad.Parts`` (glass, beam and node solids) or None; without
        parts the beams are drawn as the structure's beam quads.
    highlight : part ids drawn apart in red (:func:`part_solids`).
    """
    P, T, owner = face_triangles(mesh)
    colors = defect_colors(np.asarray(planarity, dtype=float), tolerance)[owner]
    scene = [GlbMesh("design (coloured by planarity)", P, T, colors=colors, roughness=0.6,
                     visible=parts is None),  # under the glass it would only flicker
             GlbMesh("edges", mesh.V, mesh.topology.edges, color=(0.1, 0.1, 0.12, 1.0), mode="lines")]
    if parts is not None:
        scene += part_solids(parts, frozenset(highlight))
    if structure is not None:
        Q = np.asarray(structure.beam_quads, dtype=float)
        if len(Q) and parts is None:
            e = np.arange(len(Q))[:, None] * 4
            tris = np.concatenate([e + [0, 1, 2], e + [0, 2, 3]], axis=0)
            scene.append(GlbMesh("beams", Q.reshape(-1, 3), tris, color=(0.55, 0.57, 0.62, 1.0),
                                 metallic=0.6, roughness=0.45))
        for i, L in enumerate(structure.layers):
            if i == 0 and np.allclose(L, mesh.V):
                continue
            scene.append(GlbMesh(f"layer {i} ({structure.distances[i]:g} mm)", np.asarray(L),
                                 mesh.topology.edges, color=(0.75, 0.2, 0.2, 1.0), mode="lines"))
    return scene
