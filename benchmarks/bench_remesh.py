"""Principal-direction mesh versus isoparametric grid as the start of a conical optimization.

For each roof (a triangle mesh of a height field whose principal directions
are turned away from the coordinate axes) two quad meshes of the same target
edge length are built with the same extraction and boundary handling:
``remesh`` (lines along principal directions) and ``isoparametric_remesh``
(lines ``x = i h``, ``y = j h``).  Both are optimized to a conical mesh with
the triangle surface as reference.  Printed per start mesh: faces, the initial
conical defect at interior vertices (all, and "deep": four quads, no boundary
neighbour, where boundary clipping does not count), the optimizer's status, how far the
vertices moved (max and mean, relative to the bounding-box diagonal), the
final distance to the surface and the fairness (mean second difference /
mean edge length).  The paper's claim: the principal mesh needs far less
deformation.  Also printed: the cost of the volume-PCA estimate relative to a
quadric fit on the same mesh, in the same run.

Run: ``python benchmarks/bench_remesh.py [--target conical|circular] [--h 0.3]
[--boundary glide|free|both] [--no-fine]``; a summary table, the volume-PCA
cost against a quadric fit and, on a 15k-vertex dome, the remesh time with
principal frames at sampled vertices (the default) against every vertex close
the output.  Timings are noisy on a shared machine.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # this checkout, not an installed copy

from optimize.remesh import surfaces  # noqa: E402
from optimize.api import optimize_mesh  # noqa: E402
from optimize.mesh.measures import conical_defect, fairness  # noqa: E402
from optimize.remesh.principal import principal_frames  # noqa: E402
from optimize.remesh.principal_quadric import quadric_frames  # noqa: E402
from optimize.remesh.quads import isoparametric_remesh, remesh  # noqa: E402


def turned_quadric(a: float, b: float, deg: float):
    """``z = [x y] A [x y]^T`` with eigenvalues ``a, b`` turned by ``deg``: (f, grad, hess)."""
    c, s = np.cos(np.radians(deg)), np.sin(np.radians(deg))
    Rm = np.array([[c, -s], [s, c]])
    A = Rm @ np.diag([a, b]) @ Rm.T
    return (lambda x, y: A[0, 0] * x * x + 2 * A[0, 1] * x * y + A[1, 1] * y * y,
            lambda x, y: np.stack([2 * A[0, 0] * x + 2 * A[0, 1] * y, 2 * A[0, 1] * x + 2 * A[1, 1] * y], 1),
            lambda x, y: np.broadcast_to(2 * A, (len(x), 2, 2)).copy())


def wave():
    """A free-form roof ``0.3 sin(0.8 x + 0.3 y) cos(0.6 y - 0.2 x)`` (directions vary)."""
    def f(x, y):
        return 0.3 * np.sin(0.8 * x + 0.3 * y) * np.cos(0.6 * y - 0.2 * x)

    def g(x, y):
        s, c = np.sin(0.8 * x + 0.3 * y), np.cos(0.6 * y - 0.2 * x)
        ds, dc = np.cos(0.8 * x + 0.3 * y), -np.sin(0.6 * y - 0.2 * x)
        return 0.3 * np.stack([0.8 * ds * c + s * dc * -0.2, 0.3 * ds * c + s * dc * 0.6], 1)

    def h(x, y, e=1e-5):  # central differences of the gradient (exact directions for checks)
        hx = (g(x + e, y) - g(x - e, y)) / (2 * e)
        hy = (g(x, y + e) - g(x, y - e)) / (2 * e)
        H = np.stack([hx, hy], axis=1)
        return 0.5 * (H + np.swapaxes(H, 1, 2))

    return f, g, h


ROOFS = {
    "dome (turned 30 deg)": lambda: surfaces.height_field(turned_quadric(-0.10, -0.04, 30), n=(49, 37)),
    "saddle (turned 30 deg)": lambda: surfaces.height_field(turned_quadric(0.08, -0.06, 30), n=(49, 37)),
    "wave roof": lambda: surfaces.height_field(wave(), n=(49, 37)),
}


def _deep(quads) -> np.ndarray:
    """(p,) bool over interior valence-4 vertices: all four faces quads, no neighbour on the boundary."""
    t = quads.topology
    iv = t.interior_valence4
    faces = t.star_faces[iv, :4]
    nb = t.star_neighbors[iv, :4]
    return (quads.face_sizes[faces] == 4).all(1) & ~t.is_boundary_vertex[nb].any(1)


def run_one(label, quads, corners, surface, target, glide, weights):
    """Optimize ``quads`` at each fairness weight; print a line each; return ``[(status, move, fairness)]``."""
    c0 = conical_defect(quads)
    deep = _deep(quads)
    sizes = np.bincount(quads.face_sizes)
    print(f"  {label}: {quads.n_faces} faces ({sizes[4] if len(sizes) > 4 else 0} quads), initial conical "
          f"defect max {c0.max():.3f} mean {c0.mean():.4f}, deep max {c0[deep].max():.3f} "
          f"mean {c0[deep].mean():.4f}, fairness {fairness(quads).mean():.3f}")
    out = []
    for w in weights:
        t0 = time.perf_counter()
        res = optimize_mesh(quads, target, reference=surface, glide_boundary=glide,
                            fixed=corners if glide else None, fairness=w)
        dt = time.perf_counter() - t0
        move = np.linalg.norm(res.mesh.V - quads.V, axis=1) / quads.bbox_diagonal()
        fair = float(fairness(res.mesh).mean())
        out.append((res.status, move, fair))
        print(f"    fairness weight {w:g}: {res.status:<9} {res.nit:3d} it {dt:5.1f}s  move max "
              f"{move.max():.4f} mean {move.mean():.4f}  dist {res.max_distance:.4f}  fairness {fair:.3f}")
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--target", default="conical", choices=("conical", "circular"))
    ap.add_argument("--h", type=float, default=0.3, help="target edge length (roofs are 4 x 3)")
    ap.add_argument("--boundary", default="both", choices=("glide", "free", "both"),
                    help="boundary vertices glide along the roof's outline (corners fixed), move freely, "
                         "or both runs (default)")
    ap.add_argument("--weights", default="1e-3,1e-5",
                    help="fairness weights to run (the default 1e-3 slides vertices along the surface "
                         "to even them out; 1e-5 leaves the constraints to decide)")
    ap.add_argument("--no-fine", action="store_true", help="skip the 15k-vertex sampling comparison")
    args = ap.parse_args()
    modes = {"glide": [True], "free": [False], "both": [True, False]}[args.boundary]
    weights = [float(w) for w in args.weights.split(",")]
    print(f"target {args.target}, edge length {args.h}; moves and distances relative to the bbox diagonal; "
          "fairness = mean |a - 2v + b| / mean edge")
    table = []
    for name, make in ROOFS.items():
        surf = make()
        print(f"{name}: {surf.mesh.n_vertices} vertices, {surf.mesh.n_faces} triangles")
        quads, rep = remesh(surf.mesh, args.h, side=surf.side, with_report=True)
        if rep.singular_triangles:
            print(f"  (principal field: {rep.singular_triangles} singular triangles even after smoothing)")
        elif rep.smoothing > 1:
            print(f"  (principal field smoothed over {rep.smoothing:g} h to remove its singularities)")
        grid, corners = isoparametric_remesh(surf.mesh, args.h, with_corners=True)
        for glide in modes:
            print(f" boundary {'glides' if glide else 'free'}:")
            p = run_one("principal", quads, rep.corners, surf.mesh, args.target, glide, weights)
            g = run_one("iso-grid ", grid, corners, surf.mesh, args.target, glide, weights)
            for w, (sp_, mp, fp), (sg, mg, fg) in zip(weights, p, g):
                table.append((name, "glides" if glide else "free", w, sp_, sg, mg.mean() / mp.mean(),
                              mg.max() / mp.max(), fp, fg))
    print("\nsummary: iso-grid / principal vertex moves (> 1: the principal mesh moves less); a ratio "
          "against a run that did not converge compares unequal results")
    print(f"{'roof':<24}{'boundary':<9}{'fairness':>9}  {'principal':<10}{'iso-grid':<10}{'mean move':>10}"
          f"{'max move':>9}{'fair p':>8}{'fair g':>8}")
    for name, b, w, sp_, sg, rm, rx, fp, fg in table:
        print(f"{name:<24}{b:<9}{w:>9g}  {sp_:<10}{sg:<10}{rm:>9.2f}x{rx:>8.2f}x{fp:>8.3f}{fg:>8.3f}")
    surf = ROOFS["wave roof"]()
    r = 0.3
    t0 = time.perf_counter()
    principal_frames(surf.mesh, None, r)
    t_pca = time.perf_counter() - t0
    t0 = time.perf_counter()
    quadric_frames(surf.mesh, None, r)
    t_q = time.perf_counter() - t0
    print(f"principal directions on {surf.mesh.n_vertices} vertices, r = {r}: volume PCA {t_pca:.2f}s, "
          f"quadric fit {t_q:.2f}s (PCA / quadric = {t_pca / t_q:.1f})")
    if not args.no_fine:
        fine_surface(args.h)


def fine_surface(h: float) -> None:
    """A 15k-vertex dome: frames at sampled vertices (the default) against every vertex, same run."""
    from optimize.remesh.quads import SAMPLE

    surf = surfaces.height_field(turned_quadric(-0.10, -0.04, 30), n=(141, 106))
    rows = []
    for label, sample in (("sampled", SAMPLE), ("every vertex", 0.0)):
        t0 = time.perf_counter()
        quads, rep = remesh(surf.mesh, h, side=surf.side, sample=sample, with_report=True)
        dt = time.perf_counter() - t0
        c0 = conical_defect(quads)
        rows.append(dt)
        print(f"fine dome ({surf.mesh.n_vertices} vertices), principal frames at {label}: "
              f"{rep.principal_samples} estimates, remesh {dt:.1f}s, {quads.n_faces} faces, deep initial "
              f"conical defect mean {c0[_deep(quads)].mean():.4f}")
    print(f"every vertex / sampled: remesh time x{rows[1] / rows[0]:.1f}")


if __name__ == "__main__":
    main()
