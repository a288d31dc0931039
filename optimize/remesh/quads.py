"""From a triangulated surface to a quad-dominant mesh along principal curvature lines.

The chain (paper section 5, with a practical integration step):

1. principal directions at kernel radius ``r`` by volume PCA
   (:mod:`optimize.remesh.principal`), with their reliability ``|k1 - k2|``;
2. a smooth cross field: directions kept where ``|k1 - k2|`` is large, umbilic
   and flat regions filled in (:func:`optimize.remesh.crossfield.smooth_cross_field`;
   the smoothing length grows until no singularity is left, up to 8 ``h``),
   then combed into two vector fields ``X1, X2`` per triangle;
3. integration: two scalar functions ``u, v`` on the vertices whose gradients
   follow ``X1 / h`` and ``X2 / h`` in the least-squares sense (one sparse
   factorization of the cotangent Laplacian, two solves) -- a simplified,
   integer-free global parametrization;
4. extraction: the integer iso-lines of ``u`` and ``v`` cut the surface into
   cells (:mod:`optimize.remesh.isolines`): quads inside, clipped polygons (mostly
   triangles, quads, pentagons) along the boundary.

Singularities (umbilics) that survive the smoothing are kept (``singularities=
"auto"``, the default; ``"place"`` keeps every singularity of the unsmoothed
field): steps 3-4 are replaced by :mod:`optimize.remesh.seamless` (cut from each
singular vertex to the boundary, integration with the rotation + integer
translation across the cut) and :mod:`optimize.remesh.tracing` (iso-lines traced on
the surface): an index ``+-1/4`` singularity becomes a 3-/5-gon (``irregular="faces"``,
the default) or a valence-3/5 vertex (``"vertices"``)
(``RemeshReport.method == "seamless"``, ``singularities`` lists them).  ``singularities="smooth"`` is the old behaviour.

Supported: one connected surface with one or more boundary loops (disks and
disks with holes: roofs, facades, canopies, a roof with an opening), given as
triangles or polygons (quads are split along their shorter diagonal first),
whose parameter image is one-to-one after the cuts.  Measured (tests): a roof
with a circular hole gives two boundary loops, mostly quads, conical and planar
to 1e-6 after optimization with the boundary free or gliding; a monkey saddle
gives two index -1/4 singularities near the umbilic, each a 5-gon or a
valence-5 vertex, conical after optimization; with a hole added the hole is cut
to the outer loop too; ``halftunnel.off`` (a pair of pants, three loops) gives
12 singularities and about 150 faces at ``h = 1``.
Not supported: closed surfaces; index other than +-1/4; surfaces whose
least-squares parametrization folds (the traced cells do not close:
MeshError).  The conical optimization of the remeshed ``halftunnel.off``
stalls with torsion-free beams at its irregular nodes (planarity about 1e-2);
without them it converges at some edge lengths and smoothings and folds a
face or two at others.  Slivers along the boundary are
snapped onto it in both branches (:func:`optimize.remesh.isolines.extract`,
:func:`optimize.remesh.boundary_cells.snap_slivers`), so no boundary cell keeps a
corner near 180 degrees.
Folds of the planar branch are counted in ``RemeshReport.folded`` and noted
in ``mesh.notes``.  Edge length is ``h`` where the principal field is
integrable and varies elsewhere (principal lines spread and converge): see
``RemeshReport.edge_length``.
"""
from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..api import optimize_mesh as _optimize_mesh  # the default optimizer (this package sits above the api)
from ..errors import ConfigError, MeshError
from ..mesh import Mesh, measures
from ..mesh.measures import edge_lengths
from .crossfield import comb, face_crosses, face_frames, smooth_cross_field
from .isolines import extract
from .principal import oriented_surface, principal_frames, tangent_frames

log = logging.getLogger(__name__)

IRREGULAR = ("faces", "vertices", "nearest")  # what a kept singularity becomes
SAMPLE = 0.25  # principal frames at vertices about SAMPLE * r apart on a surface finer than that

MAX_FACES = 2_000_000
"""Most faces a remeshing may make (about 5 GB and several minutes; a roof of 2,000 panels has 2,000)."""
BYTES_PER_FACE = 2_500
"""Peak memory per face made (measured: 2.1-2.2 kB a face, tracemalloc, a 2,400-triangle roof remeshed
into 129,000 and 515,000 faces)."""
MEMORY_SHARE = 0.5
"""Largest share of the machine's memory (or of the address-space limit) a remeshing may plan on."""


def machine_memory() -> int:
    """Bytes this process may use: the physical memory, or the address-space limit (``ulimit -v``)
    when that is lower."""
    import os
    import resource

    try:
        total = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (ValueError, OSError, AttributeError):
        total = 1 << 34
    soft = resource.getrlimit(resource.RLIMIT_AS)[0]
    return int(min(total, soft)) if soft not in (resource.RLIM_INFINITY, -1) and soft > 0 else int(total)


@dataclass(frozen=True)
class RemeshSize:
    """What a remeshing at ``edge_length`` would make: ``faces`` (surface ``area`` / ``edge_length^2``),
    ``bytes`` (:data:`BYTES_PER_FACE` each), and the most faces allowed here (``limit``)."""

    area: float
    edge_length: float
    faces: float
    bytes: float
    limit: int

    @property
    def ok(self) -> bool:
        return self.faces <= self.limit

    @property
    def smallest_edge(self) -> float:
        """The smallest edge length whose estimate is within the limit."""
        return math.sqrt(self.area / self.limit) if self.limit > 0 else math.inf


def remesh_size(surface: Mesh, edge_length: float) -> RemeshSize:
    """The estimate :func:`check_remesh_size` holds to its limit (nothing is allocated beyond the
    input's face areas)."""
    area = float(measures.face_areas(surface).sum())
    h = float(edge_length)
    with np.errstate(over="ignore", divide="ignore"):
        faces = area / (h * h) if h > 0 else math.inf
    limit = min(MAX_FACES, int(MEMORY_SHARE * machine_memory() / BYTES_PER_FACE))
    return RemeshSize(area=area, edge_length=h, faces=faces, bytes=faces * BYTES_PER_FACE, limit=limit)


def check_remesh_size(surface: Mesh, edge_length: float, *, key: str = "edge_length", unit: str = "",
                      per_unit: float = 1.0) -> RemeshSize:
    """Refuse (:class:`ConfigError`, exit 2) an edge length that would make more faces than
    :data:`MAX_FACES` or more than :data:`MEMORY_SHARE` of the memory, before anything is built.

    surface : the input surface; edge_length : in its coordinates.  ``key``, ``unit`` and
    ``per_unit`` (surface coordinates per ``unit``) name the value as the user gave it.
    """
    size = remesh_size(surface, edge_length)
    if size.ok:
        return size
    u = f" {unit}" if unit else " (the surface's units)"
    area = f"{size.area / per_unit ** 2:.4g}" + (f" {unit}2" if unit else "")
    cap = (f"; {MEMORY_SHARE:.0%} of the {machine_memory() / 2 ** 30:.1f} GiB this process may use"
           if size.limit < MAX_FACES else "")
    raise ConfigError(f"{surface.name}: {key} {edge_length / per_unit:.4g}{u} makes about {size.faces:,.3g} faces "
                      f"(area {area} / edge length^2; {_gib(size.bytes)} of memory), more than the {size.limit:,} "
                      f"a remeshing may make{cap}; expected an edge length of at least "
                      f"{_round_up(size.smallest_edge / per_unit)}{u}")


def _round_up(x: float) -> str:
    """``x`` to 3 significant digits, rounded up (a smallest allowed value stays allowed)."""
    if not 0 < x < math.inf:
        return f"{x:g}"
    step = 10.0 ** (math.floor(math.log10(x)) - 2)
    return f"{math.ceil(x / step * (1 - 1e-12)) * step:.3g}"


def _gib(nbytes: float) -> str:
    return f"{nbytes / 2 ** 30:,.3g} GiB" if nbytes >= 2 ** 30 else f"{nbytes / 2 ** 20:,.3g} MiB"


@dataclass
class RemeshReport:
    """Facts about one remeshing run (JSON-ready via :meth:`as_dict`)."""

    radius: float
    edge_length_target: float
    triangulated: int = 0  # polygons of the input split into triangles first
    principal_samples: int = 0  # vertices the principal frames were estimated at
    singular_triangles: int = 0
    mismatched_edges: int = 0
    folded: int = 0
    corners: list = field(default_factory=list)
    smoothing: float = 1.0
    method: str = "planar"
    singularities: list = field(default_factory=list)
    face_sizes: dict = field(default_factory=dict)
    edge_length: dict = field(default_factory=dict)
    timings: dict = field(default_factory=dict)

    def as_dict(self) -> dict:
        return {k: getattr(self, k) for k in self.__dataclass_fields__}


def gradient_operator(mesh: Mesh) -> tuple[sp.csr_matrix, np.ndarray]:
    """Per-triangle gradient ``G (3t, n)`` of piecewise linear functions, and triangle areas ``(t,)``.

    Row ``3 f + c`` is coordinate ``c`` of the (constant) gradient in triangle ``f``.  A
    degenerate triangle (area below 1e-12 of the mean, e.g. three collinear points in a
    modeller's export) has no gradient: its rows are zero and its area counts as 0.
    """
    V, F = mesh.V, mesh.F
    nf, _, _, area = face_frames(mesh)
    area = np.where(area > 1e-12 * area.mean(), area, 0.0)
    rows, cols, vals = [], [], []
    t = np.arange(len(F))
    for k in range(3):  # gradient of the hat function of corner k: n x (opposite edge) / 2A
        opp = V[F[:, (k + 2) % 3]] - V[F[:, (k + 1) % 3]]
        g = np.cross(nf, opp) / np.where(area > 0, 2 * area, np.inf)[:, None]
        for c in range(3):
            rows.append(3 * t + c)
            cols.append(F[:, k])
            vals.append(g[:, c])
    G = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                      shape=(3 * len(F), len(V)))
    return G, area


def integrate(mesh: Mesh, X1: np.ndarray, X2: np.ndarray, h: float) -> np.ndarray:
    """(n, 2) ``u, v`` minimizing ``sum_t A_t (|grad u - X1/h|^2 + |grad v - X2/h|^2)``.

    mesh : triangle Mesh; X1, X2 : (t, 3) combed unit fields.  Constants are
    fixed by a tiny mass term (mean zero).
    """
    G, area = gradient_operator(mesh)
    W = sp.diags(np.repeat(area, 3))
    K = (G.T @ W @ G).tocsc()
    eps = 1e-9 * K.diagonal().mean()
    solve = spla.factorized((K + eps * sp.identity(K.shape[0], format="csc")).tocsc())
    rhs = G.T @ W @ np.stack([X1.ravel(), X2.ravel()], 1) / h
    UV = np.stack([solve(rhs[:, 0]), solve(rhs[:, 1])], 1)
    return UV - UV.mean(0)


def folded(mesh: Mesh, UV: np.ndarray) -> np.ndarray:
    """(t,) bool: triangles whose parameter image is flipped or degenerate."""
    A = UV[mesh.F]
    d = (A[:, 1, 0] - A[:, 0, 0]) * (A[:, 2, 1] - A[:, 0, 1]) - (A[:, 1, 1] - A[:, 0, 1]) * (A[:, 2, 0] - A[:, 0, 0])
    return d <= 0


def confidence(k1: np.ndarray, k2: np.ndarray) -> np.ndarray:
    """(n,) weight in [0, 1] of the principal directions: ``min(1, |k1 - k2| / a90)^2``.

    ``a90`` is the 90th percentile of ``|k1 - k2|`` over the surface.  A
    direction error ``d`` costs a conical defect of about ``|k1 - k2| d``, so
    where the surface is nearly umbilic (or flat) the direction hardly matters
    and the smoothing decides it.
    """
    d = np.abs(k1 - k2)
    return np.minimum(1.0, d / max(float(np.percentile(d, 90)), 1e-300)) ** 2


def sample_vertices(mesh: Mesh, spacing: float) -> np.ndarray:
    """(k,) int vertices about ``spacing`` apart (one per cell of a cubic grid), or every vertex when
    that would keep more than half of them (or ``spacing`` is not positive).

    The volume-PCA estimate at radius ``r`` varies over lengths of about ``r``; on
    a surface much finer than that, estimating it at every vertex costs time
    and nothing in accuracy once the cross field is smoothed over ``h >= r``.
    """
    if not spacing > 0:
        return np.arange(mesh.n_vertices)
    key = np.floor((mesh.V - mesh.V.min(0)) / spacing).astype(np.int64)
    _, first = np.unique(key, axis=0, return_index=True)
    return np.sort(first) if len(first) < 0.5 * mesh.n_vertices else np.arange(mesh.n_vertices)


def default_radius(surface: Mesh, edge_length: float) -> float:
    """Kernel radius: the target edge length, but at least three mean triangle edges."""
    e = surface.topology.edges
    mean_edge = float(np.linalg.norm(surface.V[e[:, 1]] - surface.V[e[:, 0]], axis=1).mean())
    return max(float(edge_length), 3.0 * mean_edge)


def as_triangles(surface) -> tuple[Mesh, int]:
    """The surface as a triangle Mesh, and how many polygons were split.

    A quad is split along its shorter diagonal, a larger polygon into a fan
    from its first vertex (a quad mesh exported from a modeller is a valid
    surface input).  Triangle meshes pass through unchanged.
    """
    mesh = surface if isinstance(surface, Mesh) else Mesh(*surface)
    if mesh.F.shape[1] == 3 and not np.any(mesh.F < 0):
        return mesh, 0
    F, V, sizes = mesh.F, mesh.V, mesh.face_sizes
    tris = [F[sizes == 3, :3]]
    q = F[sizes == 4, :4]
    d02 = np.linalg.norm(V[q[:, 2]] - V[q[:, 0]], axis=1)
    d13 = np.linalg.norm(V[q[:, 3]] - V[q[:, 1]], axis=1)
    a = d02 <= d13
    tris += [q[a][:, [0, 1, 2]], q[a][:, [0, 2, 3]], q[~a][:, [0, 1, 3]], q[~a][:, [1, 2, 3]]]
    if np.any(sizes > 4):  # larger polygons: the mesh's own fan triangulation
        tris.append(Mesh(V, F[sizes > 4], name=mesh.name, check=False).triangulate())
    out = Mesh(V, np.concatenate(tris), name=mesh.name)
    return out, int(np.sum(sizes > 3))


def remesh(surface: Mesh, edge_length: float, *, radius: float | None = None, side=None,
           smoothing: float = 1.0, singularities: str = "auto", irregular: str = "faces",
           sample: float = SAMPLE,
           with_report: bool = False, name: str | None = None):
    """Quad-dominant mesh of a triangle surface (a disk, or a disk with holes) along its principal curvature lines.

    surface : triangle Mesh (or anything :func:`optimize.remesh.principal.oriented_surface` accepts).
    edge_length : target edge length ``h`` (model units).
    radius : kernel radius of the principal directions (default :func:`default_radius`).
    side : (3,) vector toward the inside (default below: ``(0, 0, -1)``).
    smoothing : smoothing length of the cross field, in units of ``h``; doubled
        (up to 8 times) while the smoothed field still has singularities.
    singularities : ``"auto"`` (smooth harder as above; singularities that
        survive become irregular vertices / faces, :mod:`optimize.remesh.seamless`),
        ``"place"`` (no extra smoothing: every singularity of the field at
        ``smoothing`` becomes an irregular vertex / face) or ``"smooth"`` (the
        old behaviour: never placed, the cells around them get distorted).
    irregular : what a kept singularity becomes: ``"faces"`` (default: a 3- or
        5-gon around it, every interior vertex keeps valence 4), ``"vertices"``
        (a valence-3 / 5 vertex) or ``"nearest"`` (whichever the rounding of the
        parametrization gives).  For conical meshes faces are the easier choice:
        a 5-gon is one more glass panel, a valence-5 node needs a cone touching
        five faces (measured, boundary free: the monkey saddle converges in 8
        iterations with faces, 25 with vertices; with a hole, 9 iterations
        against a stall).
    sample : principal frames at vertices about ``sample * r`` apart on a finer surface
        (:func:`sample_vertices`; 0: at every vertex).
    Returns the Mesh (faces counter-clockwise about the outward normal; the
    notes say what was approximated), or ``(Mesh, RemeshReport)`` with ``with_report``.
    Raises MeshError (closed, several components, or a folded seamless
    parametrization) and ConfigError (bad lengths, bad ``singularities``).
    """
    if not np.isfinite(edge_length) or edge_length <= 0:
        raise ConfigError(f"edge_length = {edge_length}, expected a positive length")
    t0 = time.perf_counter()
    surface, split = as_triangles(surface)
    check_remesh_size(surface, edge_length)  # before anything grows with the faces made
    mesh, N, closed = oriented_surface(surface, None, side)
    if closed:
        raise MeshError(f"{mesh.name}: closed surface (no boundary); remeshing supports open surfaces "
                        "with one or more boundary loops (a roof, a facade, a roof with openings): "
                        "cut it open first")
    if singularities not in ("auto", "place", "smooth"):
        raise ConfigError(f"singularities = {singularities!r}, expected 'auto', 'place' or 'smooth'")
    if irregular not in IRREGULAR:
        raise ConfigError(f"irregular = {irregular!r}, expected one of {', '.join(IRREGULAR)}")
    if edge_length >= 0.5 * mesh.bbox_diagonal():
        raise ConfigError(f"{mesh.name}: edge length {edge_length:g} is not below half the bounding-box "
                          f"diagonal {mesh.bbox_diagonal():.4g}; expected a smaller edge length")
    comps = mesh.topology.n_components
    if comps != 1:
        raise MeshError(f"{mesh.name}: {comps} components; remeshing supports one connected surface "
                        "(a disk, or a disk with holes); remesh each component on its own")
    r = default_radius(mesh, edge_length) if radius is None else float(radius)
    rep = RemeshReport(radius=r, edge_length_target=float(edge_length), triangulated=split)
    at = sample_vertices(mesh, sample * r)
    fr = principal_frames(mesh, None, r, side=side, at=at)
    rep.principal_samples = len(at)
    rep.timings["principal"] = time.perf_counter() - t0
    t1 = time.perf_counter()
    # the smoothing fills in the vertices between samples; each sample stands for n / k vertices
    conf = np.zeros(mesh.n_vertices)
    conf[at] = confidence(fr.k1, fr.k2) * (mesh.n_vertices / len(at))
    dirs = tangent_frames(N)[0]
    dirs[at] = fr.k1dir
    for grow in (1,) if singularities == "place" else (1, 2, 4, 8):  # smooth harder while singular
        arms = smooth_cross_field(mesh, N, dirs, conf, grow * smoothing * edge_length)
        X1, index = face_crosses(mesh, arms)
        if not index.any():
            break
    rep.smoothing = grow * smoothing
    if index.any() and singularities != "smooth":
        return _remesh_seamless(mesh, X1, edge_length, rep, t0, t1, name, with_report, irregular)
    X1c, mismatch = comb(mesh, X1)
    nf = face_frames(mesh)[0]
    X2 = np.cross(nf, X1c)
    t2 = time.perf_counter()
    UV = integrate(mesh, X1c, X2, edge_length)
    fold = folded(mesh, UV)
    if len(mesh.topology.boundary_loops) > 1 and singularities != "smooth" and (fold.any() or mismatch.any()):
        # around a hole the field turns or u, v have a period (a tube, a tunnel): no single-valued
        # u, v exists; the seamless branch cuts the holes open and makes the periods transitions
        rep.timings["cross_field"] = time.perf_counter() - t1
        return _remesh_seamless(mesh, X1, edge_length, rep, t0, t1, name, with_report, irregular)
    rep.singular_triangles = int(np.count_nonzero(index))
    rep.mismatched_edges = int(mismatch.sum())
    rep.folded = int(fold.sum())
    rep.timings["cross_field"] = t2 - t1
    rep.timings["integrate"] = time.perf_counter() - t2
    t3 = time.perf_counter()
    out, corners = extract(mesh, UV, name=name or f"{mesh.name}-quads")
    rep.corners = corners.tolist()
    rep.timings["extract"] = time.perf_counter() - t3
    if rep.singular_triangles or rep.folded:
        msg = (f"{out.name}: the principal field has {rep.singular_triangles} singular triangle(s) "
               f"(umbilics); the parametrization folds in {rep.folded} triangle(s); cells there are "
               "distorted (no irregular vertices are placed)")
        log.warning(msg)
        out.notes.append(msg)
    return _finish(out, rep, t0, with_report)


def _remesh_seamless(mesh, X1, edge_length, rep, t0, t1, name, with_report, irregular):
    """The seamless branch of :func:`remesh`: cut, integer-seamless ``u, v``, traced iso-lines."""
    from .boundary_cells import snap_slivers
    from .seamless import parametrize
    from .tracing import trace_quads

    rep.method = "seamless"
    P = parametrize(mesh, X1, edge_length, gradient_operator, place=irregular)
    rep.singular_triangles = int(len(P["singular"]))
    rep.mismatched_edges = P["mismatch"]
    rep.singularities = [{"vertex": int(v), "index_quarter_turns": int(k), "point": mesh.V[v].tolist()}
                         for v, k in zip(P["singular"], P["index"])]
    rep.timings["cross_field"] = time.perf_counter() - t1
    t3 = time.perf_counter()
    out, corners = trace_quads(mesh, P["UVc"], P["rot"], P["shift"], name=name or f"{mesh.name}-quads")
    out, corners = snap_slivers(out, corners, edge_length)
    out.notes.append(f"{out.name}: {int(np.sum(out.face_sizes == 4))} quads, {int(np.sum(out.face_sizes != 4))} "
                     "other faces (boundary cells, singularities), as written")
    rep.corners = corners.tolist()
    rep.timings["extract"] = time.perf_counter() - t3
    holes = len(mesh.topology.boundary_loops) - 1
    msg = (f"{out.name}: seamless parametrization, cut open from {len(P['singular'])} cross-field "
           f"singularit(ies) (indices {sorted(set(int(k) for k in P['index']))} quarter turns, placed as "
           f"irregular {'faces' if irregular == 'faces' else 'vertices or faces'}) and {holes} hole(s) to the "
           "boundary")
    log.info(msg)
    out.notes.append(msg)
    return _finish(out, rep, t0, with_report)


def isoparametric_remesh(surface: Mesh, edge_length: float, *, axes: tuple = (0, 1),
                         with_corners: bool = False, name: str | None = None):
    """The baseline: the grid of the height-field projection (lines ``x = i h``, ``y = j h``).

    Same extraction and boundary handling as :func:`remesh`, but the lines
    follow the coordinate axes ``axes`` of the projection instead of the
    principal directions.  surface : disk-like triangle Mesh whose projection
    on those axes is one-to-one (a roof).  Returns the Mesh, or ``(Mesh,
    corners (c,) int)`` with ``with_corners`` (vertices at input boundary corners).
    """
    if not np.isfinite(edge_length) or edge_length <= 0:
        raise ConfigError(f"edge_length = {edge_length}, expected a positive length")
    mesh = surface if isinstance(surface, Mesh) else Mesh(*surface)
    UV = mesh.V[:, list(axes)] / edge_length
    if folded(mesh, UV).all():
        UV = UV[:, ::-1]
    if folded(mesh, UV).any():
        raise MeshError(f"{mesh.name}: the projection on axes {tuple(axes)} is not one-to-one, "
                        "expected a height field")
    out, corners = extract(mesh, UV, name=name or f"{mesh.name}-grid")
    return (out, corners) if with_corners else out


def surface_to_mesh(surface: Mesh, edge_length: float, *, target: str = "conical",
                    radius: float | None = None, side=None, glide_boundary: bool = True,
                    irregular: str = "faces", optimizer=None, **optimize_kwargs):
    """The whole chain: triangle surface -> principal quad mesh -> conical / circular mesh.

    surface : disk-like triangle Mesh; edge_length, radius, side, irregular : as in :func:`remesh`.
    target : ``"conical"`` | ``"circular"`` | ``"pq"`` | ``"none"`` (remesh only).
    optimizer : the callable that optimizes, with the signature of :func:`optimize.api.optimize_mesh`
    (None: that function).  glide_boundary and ``optimize_kwargs`` go to it (the
    original surface is the reference); when the boundary glides and no
    ``fixed`` is given, the vertices at corners of the input boundary are fixed
    (a corner cannot glide along the boundary curve).
    Returns ``(mesh, result, report)``: the optimized Mesh (the remeshed one
    for ``"none"``), the OptimizeResult (None for ``"none"``) and the RemeshReport.
    """
    quads, rep = remesh(surface, edge_length, radius=radius, side=side, irregular=irregular, with_report=True)
    if target in (None, "none"):
        return quads, None, rep
    optimize_mesh = optimizer or _optimize_mesh
    t0 = time.perf_counter()
    if glide_boundary and optimize_kwargs.get("fixed") is None:
        optimize_kwargs["fixed"] = np.asarray(rep.corners, dtype=np.int64)
    res = optimize_mesh(quads, target, reference=surface, glide_boundary=glide_boundary, **optimize_kwargs)
    rep.timings["optimize"] = time.perf_counter() - t0
    out = res.mesh
    out.notes.extend(n for n in quads.notes if n not in out.notes)
    return out, res, rep


def _finish(out: Mesh, rep: RemeshReport, t0: float, with_report: bool):
    """Edge lengths, face sizes and total time into ``rep``; the return value of :func:`remesh`."""
    if rep.triangulated:
        out.notes.insert(0, f"{out.name}: the input's {rep.triangulated} polygon(s) were split into triangles "
                            "(quads along their shorter diagonal) before remeshing")
    el = edge_lengths(out)
    rep.edge_length = {"min": float(el.min()), "mean": float(el.mean()), "max": float(el.max())}
    rep.face_sizes = {str(k): int(c) for k, c in enumerate(np.bincount(out.face_sizes)) if c}
    rep.timings["total"] = time.perf_counter() - t0
    log.info("remesh %s: %s", out.name, rep.as_dict())
    return (out, rep) if with_report else out

