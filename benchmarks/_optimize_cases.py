"""Meshes and result rows shared by the optimizer benchmarks (``bench_optimize*.py``).

Meshes: height fields (``wave``, ``hypar``, ``conjugate``), a perturbed dome of
revolution, the shipped tunnel, ``halftunnel.off`` / ``cylinder.obj`` from
``--data DIR`` (``DATA``), a skew torus and a blob (closed, mesh lines not
conjugate).  Rows: the measured defects, distance, iterations and folds of
one run, and the table they are printed in.
"""
from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from optimize import Mesh, optimize_mesh  # noqa: E402
from optimize.mesh import measures  # noqa: E402
from optimize.modelling import shapes  # noqa: E402
from optimize.proximity import Reference  # noqa: E402

TUNNEL = ROOT / "configs" / "meshes" / "tunnel.off"  # the built-in design tunnel, in metres
DATA = None  # --data PATH: a folder with halftunnel.off and cylinder.obj (libigl tutorial meshes), else skipped


# -- meshes -------------------------------------------------------------------
def height_field(faces: int, kind: str = "wave"):
    """A square grid height field with about ``faces`` quads; not PQ.

    ``wave`` and ``hypar``: the grid lines are not a conjugate net of the surface (the
    hypar's are its rulings), so no fold-free PQ mesh lies near them; ``conjugate``:
    ``z = f(x) + g(y)`` (a translational surface, PQ as it is) with seeded noise of 10%
    of the edge length, so a fold-free PQ mesh exists close by."""
    n = int(round(np.sqrt(faces))) + 1
    size = 10.0
    if kind == "hypar":
        height = lambda x, y: 0.08 * (x - 5) * (y - 5)  # noqa: E731
    elif kind == "conjugate":
        height = lambda x, y: 0.6 * np.sin(0.7 * x) + 0.04 * (y - 5) ** 2  # noqa: E731
    else:
        height = lambda x, y: 0.6 * np.sin(0.7 * x) * np.cos(0.5 * y) + 0.02 * x * y  # noqa: E731
    mesh = shapes.grid(n, n, size=(size, size), height=height, name=f"{kind}{(n - 1) ** 2}")
    if kind == "conjugate":
        mesh = shapes.perturbed(mesh, 0.1, seed=5, name=f"{kind}{(n - 1) ** 2}+noise")
    return mesh


def revolution(faces: int, noise: float = 0.005):
    """A dome of revolution (PQ, conical, circular by construction) with seeded noise of
    ``noise`` x mean edge length (0.5%: at 10k faces the normals of neighbouring faces
    differ by under a degree, so larger noise scrambles the Gauss images completely)."""
    n = int(round(np.sqrt(faces)))
    base = shapes.revolution(shapes.dome_profile(k=n + 1), n, name=f"dome{n * n}")
    return shapes.perturbed(base, noise, seed=1, name=f"dome{n * n}+noise")


def real_mesh(path=None):
    """The shipped forking tunnel (784 quads, irregular vertices, three loops), or ``--mesh PATH``."""
    from optimize.mesh.io import read_mesh

    return read_mesh(path or TUNNEL)


def halftunnel():
    """halftunnel.off from ``--data DIR``."""
    from optimize.mesh.io import read_mesh

    return read_mesh(Path(DATA) / "halftunnel.off")


def cylinder():
    from optimize.mesh.io import read_mesh

    return read_mesh(Path(DATA) / "cylinder.obj")


def skew_torus(nu: int = 40, nv: int = 20, R: float = 3.0, r: float = 1.0):
    """A closed torus meshed by its parallels and by helices (vertex ``(i, j)`` at angles
    ``u = 2 pi (i / nu + j / nv)``, ``v = 2 pi j / nv``): the helices are not conjugate to the
    parallels, so no fold-free PQ mesh is near; closed, so it cannot be remeshed either."""
    i, j = np.meshgrid(np.arange(nu), np.arange(nv), indexing="ij")
    u, v = 2 * np.pi * (i / nu + j / nv), 2 * np.pi * j / nv
    V = np.stack([(R + r * np.cos(v)) * np.cos(u), (R + r * np.cos(v)) * np.sin(u), r * np.sin(v)], axis=-1)
    idx = lambda a, b: (a % nu) * nv + (b % nv)  # noqa: E731
    F = np.stack([idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1)], axis=-1).reshape(-1, 4)
    return Mesh(V.reshape(-1, 3), F, name=f"skew-torus{len(F)}")


def blob(n: int = 12):
    """A closed quad mesh of a smooth blob: a cube's faces cut into ``n x n`` quads, projected to
    the unit sphere and bumped (``r = 1 + 0.25 sin(2x) cos(3y) + 0.15 z^2``); its mesh lines follow
    the cube, not a conjugate net of the blob (eight valence-3 vertices)."""
    t = np.linspace(-1.0, 1.0, n + 1)
    A, B = np.meshgrid(t, t, indexing="ij")
    pts, faces, base = [], [], 0
    for axis in range(3):
        for sign in (-1.0, 1.0):
            P = np.zeros((n + 1, n + 1, 3))
            P[..., axis] = sign
            P[..., (axis + 1) % 3] = A if sign > 0 else B
            P[..., (axis + 2) % 3] = B if sign > 0 else A
            pts.append(P.reshape(-1, 3))
            k = np.arange(n)[:, None] * (n + 1) + np.arange(n)[None, :]
            faces.append(base + np.stack([k, k + n + 1, k + n + 2, k + 1], axis=-1).reshape(-1, 4))
            base += (n + 1) ** 2
    V = np.concatenate(pts)
    key = np.round(V * 1e6).astype(np.int64)
    _, first, inverse = np.unique(key, axis=0, return_index=True, return_inverse=True)
    V, F = V[first], inverse.ravel()[np.concatenate(faces)]
    V = V / np.linalg.norm(V, axis=1, keepdims=True)
    rad = 1 + 0.25 * np.sin(2 * V[:, 0]) * np.cos(3 * V[:, 1]) + 0.15 * V[:, 2] ** 2
    mesh = Mesh(V * rad[:, None], F, name=f"blob{len(F)}")
    outward = np.einsum("ij,ij->", measures.face_normals(mesh), mesh.V[mesh.F[:, 0]])
    return mesh if outward > 0 else Mesh(mesh.V, mesh.F[:, ::-1], name=mesh.name)


# -- measuring ----------------------------------------------------------------
def defect_of(mesh, target):
    if target == "conical":
        return measures.conical_defect(mesh)
    if target == "circular":
        return measures.circular_defect(mesh)
    return measures.planarity(mesh)


def row(mesh0, name, target, method, seconds, V, nit):
    out = mesh0.with_vertices(V)
    d = defect_of(out, target)
    p = measures.planarity(out)
    dist = Reference(mesh0).distance(V).max() / mesh0.bbox_diagonal()
    return {"mesh": name, "faces": mesh0.n_faces, "target": target, "method": method,
            "seconds": seconds, "max": float(d.max()), "mean": float(d.mean()),
            "planarity": float(p.max()), "distance": float(dist), "nit": nit,
            "folded": int(measures.folded_faces(mesh0, np.asarray(V, dtype=float)).sum())}


def ours(mesh, target, **kw):
    t = time.perf_counter()
    res = optimize_mesh(mesh, target, **kw)
    r = row(mesh, mesh.name, target, "ours", time.perf_counter() - t, res.mesh.V, res.nit)
    r["status"] = res.status
    return r


def result_row(mesh0, name, target, method, seconds, res):
    """A row from an OptimizeResult (any connectivity: the remeshed route's too)."""
    d = res.defects
    out = res.mesh
    p = measures.planarity(out)
    return {"mesh": name, "faces": out.n_faces, "target": target, "method": method, "seconds": seconds,
            "max": float(defect_of(out, target).max()), "mean": float(defect_of(out, target).mean()),
            "planarity": float(p.max()), "distance": float(d["distance"]["max_relative"]), "nit": res.nit,
            "folded": int(d["folded"]["count"]), "status": res.status,
            "fair": f"fair {d['fairness']['input']:.3g}->{d['fairness']['result']:.3g}"}


def print_table(rows, percent: bool = True):
    """``dist``: max distance to the input surface in % of its bbox diagonal."""
    head = f"{'mesh':22s} {'faces':>7s} {'target':8s} {'method':8s} {'time s':>8s} {'max':>9s} " \
           f"{'mean':>9s} {'planar':>9s} {'dist %':>8s} {'nit':>5s} {'fold':>4s}  status / ratio / note"
    print(head)
    print("-" * len(head))
    for r in rows:
        extra = "; ".join(x for x in (r.get("status", ""), r.get("fair", ""), r.get("ratio", ""),
                                      r.get("note", "")) if x)
        print(f"{r['mesh'][:22]:22s} {r['faces']:7d} {r['target']:8s} {r['method']:8s} "
              f"{r['seconds']:8.2f} {r['max']:9.2e} {r['mean']:9.2e} {r['planarity']:9.2e} "
              f"{100 * r['distance']:8.3f} {r['nit']:5d} {r.get('folded', 0):4d}  {extra}", flush=True)
