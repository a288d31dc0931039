"""Schedules a glass supplier and a steel shop order from (CSV, mm, degrees, kg).

- ``glass_schedule.csv``: one row per glass unit (a panel, whatever its
  build-up): the build-up (``10/16/88.4`` and spelled out), its total
  thickness (cavity included), its solids (``P0001.1 ...``: plies and
  interlayers, outside in), the spacer setback of an insulated unit (edge
  seal width), area, the stock blank (of its largest ply), per edge (in the order of the bearing face, counter-clockwise
  seen from the beams) its length, the corner angle at its start, its bevel
  (degrees from square, positive when the face away from the beams is the
  smaller one), the beam under it and the neighbouring panel across it;
  weight (every ply and interlayer: volume x density; spacer and seal not
  included), warp (mm: distance between the diagonals of the mesh face, the
  planarity times the mean diagonal; n-gons: twice the largest distance from
  the plane), the limits it breaks.
- ``steel_cut_list.csv``: one row per beam: section, grade, length (node axis
  to node axis along the glass edge), the stock blank, both end cuts as mitre
  (in the plate, degrees from square, positive when the beam is longer on the
  glass side) and bevel (through the thickness, ``+`` and ``-`` side), the
  ridge under the glass, the dihedral between the two panels it carries
  (inside the beam; 180 flat), weight, the limits it breaks.
- ``node_schedule.csv``: one row per node: position, axis direction (glass
  toward beams), the incoming beams with their angle around the axis
  (azimuth, from the first one, counter-clockwise seen along the axis) and
  their elevation from the plane normal to the axis, the hub.
"""
from __future__ import annotations

import csv
import time
from pathlib import Path

import numpy as np

from optimize.atomic import atomic_open
from optimize.errors import ExportError

from fabricate.cad.geometry import polygon_area_2d
from fabricate.cad.limits import corner_angles_deg, edge_lengths

GLASS_COLUMNS = ("id", "face", "build_up", "thickness_mm", "solids", "spacer_setback_mm", "area_m2", "blank_w_mm",
                 "blank_h_mm", "edge_lengths_mm", "corner_angles_deg", "edge_bevels_deg", "beams", "neighbours",
                 "weight_kg", "warp_mm", "planarity", "flags")
STEEL_COLUMNS = ("id", "edge", "section", "grade", "length_mm", "blank_w_mm", "blank_h_mm",
                 "end_a_mitre_deg", "end_a_bevel_deg", "end_b_mitre_deg", "end_b_bevel_deg", "top_bevel_deg",
                 "dihedral_deg", "weight_kg", "panels", "nodes", "flags")
NODE_COLUMNS = ("id", "vertex", "x_mm", "y_mm", "z_mm", "axis_x", "axis_y", "axis_z", "valence", "beams",
                "azimuth_deg", "elevation_deg", "hub")


def _flags(parts) -> dict[str, list[str]]:
    out: dict[str, list[str]] = {}
    for key, entry in (parts.report.get("limits") or {}).items():
        for pid in entry.get("ids", []):
            out.setdefault(pid, []).append(f"{key} {entry['limit']}")
    return out


def _write(path: Path, columns, rows) -> int:
    try:
        with atomic_open(path, "w", encoding="utf-8", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(columns)
            n = 0
            for row in rows:  # one CSV row per part
                w.writerow(row)
                n += 1
    except OSError as exc:
        raise ExportError(f"{path}: cannot write the schedule ({exc.strerror or exc})") from None
    return n


def _num(values, fmt: str = "{:.1f}") -> str:
    return " ".join(fmt.format(float(v)) for v in values)


def warp_mm(mesh, faces: np.ndarray) -> np.ndarray:
    """(q,) mm: distance between the diagonals of quad faces, twice the largest distance from the
    least-squares plane of other faces (``mesh`` in mm)."""
    sizes = mesh.face_sizes[faces]
    out = np.zeros(len(faces))
    q = sizes == 4
    if q.any():
        P = mesh.V[mesh.F[faces[q], :4]]
        d1, d2 = P[:, 2] - P[:, 0], P[:, 3] - P[:, 1]
        c = np.cross(d1, d2)
        out[q] = np.abs(((P[:, 1] - P[:, 0]) * c).sum(axis=1)) / np.maximum(np.linalg.norm(c, axis=1), 1e-300)
    for k in np.unique(sizes[~q]).tolist():  # one batch per other face size
        sel = np.nonzero(sizes == k)[0]
        P = mesh.V[mesh.F[faces[sel], :k]]
        C = P - P.mean(axis=1, keepdims=True)
        n = np.linalg.svd(C)[2][:, -1]
        out[sel] = 2 * np.abs(np.einsum("pki,pi->pk", C, n)).max(axis=1)
    return out


def mean_diagonal(mesh, faces: np.ndarray) -> np.ndarray:
    sizes = mesh.face_sizes[faces]
    P = mesh.V[np.maximum(mesh.F[faces], 0)]
    out = np.zeros(len(faces))
    for k in np.unique(sizes).tolist():  # per face size
        sel = np.nonzero(sizes == k)[0]
        Q = P[sel, :k]
        if k == 4:
            out[sel] = 0.5 * (np.linalg.norm(Q[:, 2] - Q[:, 0], axis=1) + np.linalg.norm(Q[:, 3] - Q[:, 1], axis=1))
        else:
            out[sel] = np.linalg.norm(np.roll(Q, -1, axis=1) - Q, axis=2).mean(axis=1)
    return out


def build_up_text(spec) -> str:
    """The glass build-up as a supplier writes it (``insulated 10/16/88.4 (10 | 16 argon | 8 + 1.52 PVB + 8 ...)``)."""
    return spec.glass.describe()


def write_glass_schedule(parts, path) -> dict:
    """Write ``glass_schedule.csv`` (atomic).  Returns facts: ``file, bytes, rows, seconds``."""
    t0 = time.perf_counter()
    path = Path(path)
    from fabricate.cad.glass import bearing_groups, unit_sums
    from fabricate.cad.parts import unit_id

    flags: dict[str, list[str]] = {}
    for pid, fl in _flags(parts).items():  # a ply's flags are its unit's
        flags.setdefault(unit_id(pid), []).extend(f for f in fl if f not in flags.get(unit_id(pid), []))
    beam_panels = {pid: [unit_id(n) for n in g.neighbours[i] if n[0] == "P"]
                   for g in parts.of_kind("beam") for i, pid in enumerate(g.ids)}
    spec = parts.spec
    build_up = build_up_text(spec)
    solids = spec.glass.solids()
    seal = f"{spec.glass.edge_seal_mm:g}" if spec.glass.type == "insulated" else ""
    mesh = parts.mesh
    weight_of = unit_sums(parts, lambda g: g.volume_mm3 * spec.group_density(g) * 1e-9)
    glass = [g for g in parts.of_kind("panel") if not g.material]
    blank_area = unit_sums(parts, lambda g: np.zeros(len(g)))
    blank = np.zeros((len(blank_area), 2))
    for g in glass:  # the unit's blank: its largest ply's
        a = g.rect.prod(axis=1)
        bigger = a > blank_area[g.element]
        blank_area[g.element[bigger]] = a[bigger]
        blank[g.element[bigger]] = g.rect[bigger]

    def rows():
        for g in bearing_groups(parts):
            L, A = edge_lengths(g.bevel_ref), corner_angles_deg(g.bevel_ref)
            area = polygon_area_2d(g.bevel_ref)                # the glass (bearing face), not the blank
            side = g.cuts[:, 0] - 2                       # the side face (and beam) under each edge
            bevel = g.bevel_deg[..., 1]
            weight = weight_of[g.element]
            warp = warp_mm(mesh, g.element) if mesh is not None else 2 * g.planarity_mm
            diag = mean_diagonal(mesh, g.element) if mesh is not None else np.ones(len(g))
            for i, ply in enumerate(g.ids):
                pid = unit_id(ply)
                beams = [b for b in g.neighbours[i] if b[0] == "B"]
                beams = [beams[s] for s in side.tolist()]
                across = [next((p for p in beam_panels.get(b, []) if p != pid), "-") for b in beams]
                members = " ".join(f"{pid}.{k + 1}" for k in range(len(solids))) if len(solids) > 1 else pid
                yield (pid, int(g.element[i]), build_up, f"{spec.glass.thickness_mm:.2f}", members, seal,
                       f"{area[i] * 1e-6:.4f}", f"{blank[g.element[i], 0]:.1f}", f"{blank[g.element[i], 1]:.1f}",
                       _num(L[i]), _num(A[i]), _num(bevel[i], "{:+.2f}"), " ".join(beams), " ".join(across),
                       f"{weight[i]:.1f}", f"{warp[i]:.3g}", f"{warp[i] / diag[i]:.2e}",
                       "; ".join(flags.get(pid, [])))
    n = _write(path, GLASS_COLUMNS, rows())
    return {"file": path.name, "bytes": path.stat().st_size, "rows": n, "build_up": build_up,
            "build_up_short": spec.glass.short(), "unit_thickness_mm": spec.glass.thickness_mm,
            "solids_per_unit": len(solids), "seconds": time.perf_counter() - t0}


def beam_angles(g) -> dict[str, np.ndarray]:
    """End cuts and dihedrals of a beam group (degrees): ``mitre (p, 2)`` at ends a, b (positive: longer
    on the glass side), ``end_bevel (p, 2, 2)`` [end, side], ``top_bevel (p, 2)``, ``dihedral (p,)``."""
    R = g.bevel_ref                                          # A0, B0, B1, A1 in the plate
    t = R[:, 1] - R[:, 0]
    t = t / np.linalg.norm(t, axis=1, keepdims=True)

    def along(e):
        return np.einsum("pi,pi->p", t, e / np.linalg.norm(e, axis=1, keepdims=True))

    mitre_a = -np.degrees(np.arcsin(np.clip(along(R[:, 0] - R[:, 3]), -1, 1)))
    mitre_b = -np.degrees(np.arcsin(np.clip(along(R[:, 2] - R[:, 1]), -1, 1)))
    n_p, n_m = g.normals[:, 2], g.normals[:, 3]             # T0+ and T0- (the glass bears on them)
    dihedral = 180.0 - np.degrees(np.arccos(np.clip(np.einsum("pi,pi->p", n_p, n_m), -1, 1)))
    return {"mitre": np.stack([mitre_a, mitre_b], axis=1), "end_bevel": g.bevel_deg[:, [3, 1]],
            "top_bevel": g.bevel_deg[:, 0], "dihedral": dihedral}


def write_steel_cut_list(parts, path) -> dict:
    """Write ``steel_cut_list.csv`` (atomic).  Returns facts: ``file, bytes, rows, seconds``."""
    t0 = time.perf_counter()
    path = Path(path)
    flags = _flags(parts)
    spec = parts.spec
    topo = parts.mesh.topology if parts.mesh is not None else None
    from fabricate.cad.parts import part_ids, unit_id

    def rows():
        for g in parts.of_kind("beam"):
            a = beam_angles(g)
            weight = g.volume_mm3 * spec.group_density(g) * 1e-9
            length = np.linalg.norm(g.bevel_ref[:, 1] - g.bevel_ref[:, 0], axis=1)
            nodes = (part_ids("node", topo.edges[g.element].ravel()) if topo is not None else ())
            for i, pid in enumerate(g.ids):
                panels = [unit_id(n) for n in g.neighbours[i] if n[0] == "P"]
                two = len(panels) == 2
                yield (pid, int(g.element[i]), f"plate {spec.beam_width:g} x {g.rect[i, 1]:.0f}", spec.steel_grade,
                       f"{length[i]:.1f}", f"{g.rect[i, 0]:.1f}", f"{g.rect[i, 1]:.1f}",
                       f"{a['mitre'][i, 0]:+.2f}", _num(a["end_bevel"][i, 0], "{:+.2f}"),
                       f"{a['mitre'][i, 1]:+.2f}", _num(a["end_bevel"][i, 1], "{:+.2f}"),
                       _num(a["top_bevel"][i], "{:+.2f}"), f"{a['dihedral'][i]:.2f}" if two else "",
                       f"{weight[i]:.2f}", " ".join(panels), " ".join(nodes[2 * i:2 * i + 2]) if nodes else "",
                       "; ".join(flags.get(pid, [])))
    n = _write(path, STEEL_COLUMNS, rows())
    return {"file": path.name, "bytes": path.stat().st_size, "rows": n, "seconds": time.perf_counter() - t0}


def node_table(parts) -> dict[str, np.ndarray]:
    """Per beam end: ``vertex (2e,)``, ``beam (2e,)`` ids index, ``axis (2e, 3)`` unit (glass toward beams),
    ``direction (2e, 3)`` unit from the node along the beam's glass edge, sorted by vertex."""
    gs = parts.of_kind("beam")
    X = np.concatenate([g.vertices for g in gs])
    ids = np.array([i for g in gs for i in g.ids])
    E = parts.mesh.topology.edges[np.concatenate([g.element for g in gs])]
    vert = np.concatenate([E[:, 0], E[:, 1]])
    axis = np.concatenate([X[:, 3] - X[:, 0], X[:, 2] - X[:, 1]])
    direction = np.concatenate([X[:, 1] - X[:, 0], X[:, 0] - X[:, 1]])
    beam = np.concatenate([ids, ids])
    order = np.argsort(vert, kind="stable")
    unit = lambda v: v / np.linalg.norm(v, axis=1, keepdims=True)  # noqa: E731
    return {"vertex": vert[order], "beam": beam[order], "axis": unit(axis[order]),
            "direction": unit(direction[order])}


def write_node_schedule(parts, path) -> dict:
    """Write ``node_schedule.csv`` (atomic).  Returns facts: ``file, bytes, rows, seconds``."""
    from fabricate.cad.beams import _node_frames
    from fabricate.cad.parts import part_ids

    t0 = time.perf_counter()
    path = Path(path)
    mesh = parts.mesh
    if mesh is None or not parts.of_kind("beam"):
        raise ExportError(f"{path}: no beams or no mesh: nothing to schedule")
    nt = node_table(parts)
    v = nt["vertex"]
    first = np.searchsorted(v, v, side="left")
    axis = nt["axis"][first]                                 # one axis per node (the same line for all)
    fx, fy = _node_frames(axis)
    d = nt["direction"]
    elev = np.degrees(np.arcsin(np.clip(np.einsum("pi,pi->p", d, axis), -1, 1)))
    az = np.degrees(np.arctan2(np.einsum("pi,pi->p", d, fy), np.einsum("pi,pi->p", d, fx)))
    az = (az - az[first]) % 360.0
    order = np.lexsort((az, v))
    v, az, elev, beam, axis = v[order], az[order], elev[order], nt["beam"][order], axis[order]
    starts = np.flatnonzero(np.r_[True, v[1:] != v[:-1]])
    stops = np.r_[starts[1:], len(v)]
    nid = part_ids("node", np.arange(mesh.n_vertices))
    hub = f"hub r {parts.spec.node_radius:g} mm" if parts.spec.node_radius > 0 else "none (mitred ends)"

    def rows():
        for s, e in zip(starts.tolist(), stops.tolist()):  # one row per node
            i = int(v[s])
            x = mesh.V[i]
            a = axis[s]
            yield (nid[i], i, f"{x[0]:.1f}", f"{x[1]:.1f}", f"{x[2]:.1f}", f"{a[0]:.6f}", f"{a[1]:.6f}",
                   f"{a[2]:.6f}", e - s, " ".join(beam[s:e]), _num(az[s:e]), _num(elev[s:e]), hub)
    n = _write(path, NODE_COLUMNS, rows())
    return {"file": path.name, "bytes": path.stat().st_size, "rows": n, "seconds": time.perf_counter() - t0}
