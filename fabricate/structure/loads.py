"""Loads on the frame: the basic cases (EN 1991-style) and their combinations (EN 1990-style).

Units in: kN/m3 and kN/m2 (config); out: N and mm (N/mm line loads).  A panel's load goes to
the beams on its edges in proportion to the edge lengths (the tributary split of a panel
bearing on all its sides: each edge carries ``F_f * l / perimeter``), as a uniform line load
on each beam; totals are exact, so the sum of the reactions is the sum of the loads.

- ``self_weight``: steel unit weight x section area, downward (``-up``), per beam;
- ``glass``: glass unit weight x thickness x panel area, downward;
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


def panel_forces_to_beams(mesh, forces: np.ndarray, n_edges: int) -> np.ndarray:
    """(e, 3) float total force on each beam from the panel ``forces (m, 3)`` (N), split over each
    panel's edges in proportion to their lengths."""
    t = mesh.topology
    V = np.asarray(mesh.V)
    ell = np.linalg.norm(V[t.corner_next_vertex] - V[t.corner_vertex], axis=1)
    perim = np.bincount(t.corner_face, weights=ell, minlength=mesh.n_faces)
    share = ell / perim[t.corner_face]
    out = np.zeros((n_edges, 3))
    np.add.at(out, t.corner_edge, forces[t.corner_face] * share[:, None])
    return out


def basic_cases(structure, frame, loads, glass_thickness: float, up=(0.0, 0.0, 1.0)) -> dict[str, LoadCase]:
    """The basic load cases ``{name: LoadCase}`` (see the module docstring) of the frame
    ``frame`` built on ``structure`` (an OffsetStructure); ``loads`` a LoadsOption (kN/m3, kN/m2),
    ``glass_thickness`` mm."""
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
    }
    zeros = np.zeros((n, 6))
    cases = {"self_weight": LoadCase("self_weight", zeros,
                                     -u[None, :] * (loads.steel_unit_weight * KN_M3 * frame.prop("A"))[:, None])}
    for name, F in per_area.items():
        cases[name] = LoadCase(name, zeros, panel_forces_to_beams(mesh, F, e) / L[:, None])
    return cases
