"""``optimize_mesh``: make a mesh PQ, conical or circular, fair and close to a reference.

The default method is the regularized Gauss-Newton of :mod:`optimize.solvers.guided`
on the quadratic formulation of :mod:`optimize.terms.formulation`, built from the
run's problem description (:func:`optimize.terms.problem.describe`: unknowns,
normalization, fixed vertices, rows, energies).  The paper's own
methods (``"penalty"``, ``"sqp"``, ``"hybrid"``) live in ``optimize.solvers.paper`` and
are imported only when asked for.
"""
from __future__ import annotations

import logging
import time

import numpy as np

from .errors import ConfigError
from .mesh import Mesh, measures
from .mesh import symmetry
from .mesh.axes import fit_axes
from .options import DEFAULTS, FORMULATIONS, METHODS, OptimizeOptions  # noqa: F401 (re-exported)
from .proximity.curve import BoundaryCurve
from .proximity.surface import Reference
from .mesh.conjugacy import record_net
from .result import OptimizeResult, check_folds, record_shape
from .solvers import fairing, guided
from .solvers.rationalize import rationalize as rationalize_run
from .solvers.guided import Convex, Glide, solve
from .terms import convexity
from .terms import fixed as fixed_mod
from .terms.formulation import Formulation
from .terms.problem import GLIDE_EDGE_FLOOR, describe, resolve_formulation  # noqa: F401 (re-exported)
from .tolerances import Tolerances

log = logging.getLogger(__name__)

FOLD_ADVICE = ("the convexity rows should have prevented this: please report it; remeshing along "
               "principal directions (input.remesh) gives a mesh a fold-free PQ mesh is near")
NO_CONVEX_FOLD_ADVICE = ("run with convexity kept (drop --no-convex / convex=False): faces then stay convex "
                         "and where that leaves them non-planar the run names them")

HELD_ADVICE = ("what helps: remeshing along principal directions (--remesh auto, input.remesh: auto), "
               "or the paper's penalty method (--method penalty), which sometimes finds one")


def optimize_mesh(mesh: Mesh, target: str = DEFAULTS.target, *, method: str = DEFAULTS.method,
                  reference: Mesh | None = None, fixed=None, glide_boundary: bool = DEFAULTS.glide_boundary,
                  fairness: float = DEFAULTS.fairness, closeness: float = DEFAULTS.closeness,
                  tol: Tolerances = DEFAULTS.tol, max_iter: int = DEFAULTS.max_iter, callback=None,
                  linear_solver: str = DEFAULTS.linear_solver, formulation: str = DEFAULTS.formulation,
                  torsion_free_beams=DEFAULTS.torsion_free_beams, convex: bool = DEFAULTS.convex,
                  refine=DEFAULTS.refine, rationalize=DEFAULTS.rationalize, **options) -> OptimizeResult:
    """Move the vertices of ``mesh`` so that it becomes ``target``; never mutates ``mesh``.

    mesh : Mesh, quads with n-gons and triangles allowed, boundary allowed.
    target : ``"pq"`` (every face planar) | ``"conical"`` (PQ, and the faces
        around every interior valence-4 vertex tangent to one cone) |
        ``"circular"`` (PQ, and every quad has a circumcircle).
    method : ``"default"`` (regularized Gauss-Newton) | ``"penalty"`` | ``"sqp"`` |
        ``"hybrid"`` (the paper's methods, ``optimize.solvers.paper``).
    reference : Mesh or None.  Surface the vertices stay close to (the input
        when None); triangulated inside.
    fixed : None | "none" | "boundary" | "corners" | (k,) int vertex indices that do not move.
    glide_boundary : keep free boundary vertices on the reference's boundary curve
        (corner vertices, with one face, are then fixed); boundary edges at
        gliding vertices keep at least ``GLIDE_EDGE_FLOOR`` of their start
        length (a one-sided row, :mod:`optimize.terms.edgefloor`), so a
        vertex cannot slide onto its neighbour or into a corner.
    fairness, closeness : weights of the scale-free fairness and tangent-plane
        closeness energies relative to the constraints (halved every iteration; the
        fairness weight also scaled by the worst defect over ``guided.FAR``, so a mesh
        nearly there keeps its shape).  With ``refine`` a converged run then minimizes
        fairness relative to the input plus closeness, balanced by their ratio, with every
        constraint kept exact.
    tol : Tolerances; the run converges when every defect of the target is within it.
    max_iter : iteration budget.
    callback : ``callback(entry: dict)`` after each iteration.
    linear_solver : one of ``optimize.options.LINEAR_SOLVERS`` (default method only);
        ``"auto"`` is MKL PARDISO where installed, else SciPy's SuperLU.
    formulation : ``"auxiliary"`` (quadratic rows on positions plus unit normals,
        cone axes, circle centres), ``"vertices"`` (positions only) or ``"auto"``
        (``"vertices"`` for conical, else ``"auxiliary"``); default method only.
    torsion_free_beams : conical with the vertex formulation: node axes become unknowns
        at every vertex, with the cone condition at every valence and every beam
        planar (``terms.nodeaxes``); the result then carries them in
        ``beam_axes`` for the offset stage.  ``"auto"``: when the
        mesh has interior vertices of valence other than 4 (where the paper's angle
        balance says nothing and beams would twist).
    convex : keep every corner that is convex in the input convex (default method:
        one-sided rows, ``terms.convexity``, and no accepted step folds a face);
        ``False`` is the earlier behaviour (planar, perhaps dented; then ``folded``).
        Where no fold-free mesh is near, the run ends ``stalled`` / ``max_iter`` and
        ``defects["convexity"]`` names the faces held at their convexity floor.
    rationalize : None, or the pull (model units): after a converged solve, faces within it of each
        other at every corner are pulled into exact classes of one shape, every constraint kept
        (default method; :mod:`optimize.solvers.rationalize`, ``defects["rationalize"]``).
    The default method keeps the input's rigid symmetries (:mod:`optimize.mesh.symmetry`): a
    result that is no longer symmetric (the closeness term's footpoints on the fan-triangulated
    reference are not mirror-invariant) is projected onto the symmetric positions and solved
    again from there (``defects["symmetry"]``).
    options : extras of the paper's methods (``mu``, ``kkt_tol``, ...), passed on
        to ``optimize.solvers.paper.run_paper_method``; none for the default method.

    Returns :class:`OptimizeResult` (``success`` only when every tolerance is met).
    Raises :class:`ConfigError` for unknown target, method, fixed or solver values.
    The keywords are those of :class:`optimize.options.OptimizeOptions` (their defaults
    are its defaults); :func:`run` takes such an object.
    """
    opts = OptimizeOptions(target=target, method=method, fairness=fairness, closeness=closeness,
                           max_iter=max_iter, tol=tol, linear_solver=linear_solver, formulation=formulation,
                           torsion_free_beams=torsion_free_beams, convex=convex, glide_boundary=glide_boundary,
                           refine=refine, rationalize=rationalize, paper=options)
    return run(mesh, opts, reference=reference, fixed=fixed, callback=callback)


def _refines(refine, run, ref, form, tol: Tolerances) -> bool:
    """Whether the constrained fairing phase follows the guided solve: ``refine`` True, or ``"auto"``
    and the converged result lies further from the reference than ``tol.closeness`` (a result that
    is close already is left as it is: the phase costs 5-30 x the solve)."""
    if refine is False or run.status != "converged" or ref is None:
        return False
    if refine is True:
        return True
    V = form.layout.view(run.x, "vertices")
    return float(ref.distance(V).max() / ref.bbox_diagonal) > tol.closeness


def run(mesh: Mesh, opts: OptimizeOptions = DEFAULTS, *, reference: Mesh | None = None, fixed=None,
        callback=None) -> OptimizeResult:
    """Optimize ``mesh`` with the settings ``opts`` (:class:`optimize.options.OptimizeOptions`).

    reference, fixed, callback : as in :func:`optimize_mesh`.  The default method runs
    here; the paper's methods in ``optimize.solvers.paper`` (imported only then).
    """
    if opts.method != "default":
        return _paper(mesh, opts.target, method=opts.method, reference=reference, fixed=fixed,
                      glide_boundary=opts.glide_boundary, fairness=opts.fairness, closeness=opts.closeness,
                      tol=opts.tol, max_iter=opts.max_iter, callback=callback, **opts.paper)
    target, tol, formulation, linear_solver = opts.target, opts.tol, opts.formulation, opts.linear_solver
    fairness, closeness, max_iter = opts.fairness, opts.closeness, opts.max_iter
    glide_boundary, torsion_free_beams, convex = opts.glide_boundary, opts.torsion_free_beams, opts.convex
    method = opts.method
    if linear_solver == "pardiso":
        from .linalg import pardiso

        if not pardiso.available():
            raise ConfigError(f"linear_solver: 'pardiso' needs Intel MKL, which did not load "
                              f"({pardiso.load_error()}); install the 'mkl' package or use 'auto' / 'superlu'")
    t0 = time.perf_counter()
    spec = describe(mesh, target, "default", formulation=formulation, beams=torsion_free_beams, fixed=fixed,
                    glide_boundary=glide_boundary, convex=convex, fairness=fairness, closeness=closeness,
                    reference=reference)
    centre, h = spec.centre, spec.scale
    norm = spec.normalized()
    ref_mesh = reference if reference is not None else mesh
    ref_norm = ref_mesh.with_vertices((ref_mesh.V - centre) / h) if reference is not None else norm
    ref = Reference(ref_norm)
    _check_meetable(mesh, target, fixed, fixed_mod.resolve(mesh, fixed), tol)
    fixed_idx = spec.fixed  # with a gliding boundary, its corners too
    listed = {t.module for t in spec.terms}
    glide = None
    if "glide" in listed:  # the vertices and edges the description chose; the curve and floors here
        E = spec.sets["glide_edges"]
        floor = GLIDE_EDGE_FLOOR * np.linalg.norm(norm.V[E[:, 0]] - norm.V[E[:, 1]], axis=1)
        glide = Glide(spec.sets["glide"], BoundaryCurve(ref_norm), E, floor)
    form = Formulation(norm, target, spec=spec)
    x0 = form.start(norm.V)
    keep = None
    if "convexity" in listed:
        corners, floor = convexity.floors(norm, norm.V, tol.fold)
        keep = Convex(corners, floor, norm.V)
    t_setup = time.perf_counter() - t0
    group = _group(norm, fixed_idx)
    run = solve(form, x0, ref=ref, glide=glide, tol=tol, max_iter=int(max_iter), callback=callback,
                backend=linear_solver, convex=keep, far=guided.FAR)
    if _refines(opts.refine, run, ref, form, tol):  # exact, fair and close: the constrained fairing phase
        run = fairing.refine(form, run, x0, ref=ref, glide=glide, convex=keep, tol=tol, fairness=fairness,
                             closeness=closeness, callback=callback)
    sym = rat = None
    if not group.trivial:
        run, sym = _keep_symmetry(form, run, group, glide, keep, tol, linear_solver, callback)
    if opts.rationalize is not None:
        limit = tol.closeness_mm if tol.closeness_mm is not None else tol.closeness * ref.bbox_diagonal * h
        run, rat = rationalize_run(form, run, x0, ref=ref, glide=glide, convex=keep, tol=tol, fairness=fairness,
                                   closeness=closeness, pull=opts.rationalize, scale=h, limit=limit,
                                   group=None if group.trivial else group, callback=callback)
        if not group.trivial and rat["rounds"]:
            run, sym2 = _keep_symmetry(form, run, group, glide, keep, tol, linear_solver, callback)
            sym["after_rationalize"] = sym2
    L = form.layout
    Xn = L.view(run.x, "vertices")
    V = Xn * h + centre if run.nit else mesh.V.copy()  # no step taken: bit-exact input
    V[fixed_idx] = mesh.V[fixed_idx]  # bit-exact: fixed means fixed
    out = mesh.with_vertices(V)
    t1 = time.perf_counter()
    normals = (_unit(L.view(run.x, "normals")) if "normals" in L
               else measures.face_normals(norm, Xn))
    axes = cone_angles = beam_axes = None
    if target == "conical":
        axes, cone_angles = _node_axes(form, run.x, normals)
    if len(form.axis_vertices):
        beam_axes = np.full((mesh.n_vertices, 3), np.nan)
        beam_axes[form.axis_vertices] = axes[form.axis_vertices]
    dist = ref.distance(Xn)  # the footpoint search once: the headline and the per-vertex record share it
    max_distance = float(dist.max() / ref.bbox_diagonal)
    defects = measures.summary(out, tol)
    timings = dict(run.timings, setup=t_setup, report=time.perf_counter() - t1,
                   total=time.perf_counter() - t0)
    res = OptimizeResult(mesh=out, success=run.status == "converged", status=run.status,
                         message=run.message, nit=run.nit, history=run.history, defects=defects,
                         max_distance=max_distance, normals=normals, axes=axes, cone_angles=cone_angles,
                         beam_axes=beam_axes, timings=timings, method=method, target=target)
    record_shape(res, mesh, dist * h, ref.bbox_diagonal * h)
    if sym is not None:
        res.defects["symmetry"] = sym
    if rat is not None:
        res.defects["rationalize"] = rat
    record_net(res, mesh, target)
    if keep is not None:
        _held(res, norm, Xn, keep, tol)
    check_folds(res, mesh.V, FOLD_ADVICE if convex else NO_CONVEX_FOLD_ADVICE, tol.fold)
    log.info("optimize_mesh(%s, %s): %s", mesh.name, target, res.message)
    return res


def _check_meetable(mesh: Mesh, target: str, fixed, fixed_idx: np.ndarray, tol: Tolerances) -> None:
    """Refuse, before the first iteration, a fixed set no iteration can meet: a face whose
    vertices are all fixed but that is not planar (for ``circular``: not circular) now.
    Raises :class:`ConfigError` naming the faces."""
    if not len(fixed_idx):
        return
    pinned = np.zeros(mesh.n_vertices, dtype=bool)
    pinned[fixed_idx] = True
    F = mesh.F
    allfixed = np.where(F >= 0, pinned[np.maximum(F, 0)], True).all(axis=1)
    if not allfixed.any():
        return
    bad = allfixed & (measures.planarity(mesh) > tol.planarity)
    what = "planar"
    if target == "circular" and not bad.any():
        circ = np.zeros(mesh.n_faces)
        circ[mesh.face_sizes == 4] = measures.circular_defect(mesh)
        bad, what = allfixed & (circ > tol.circular), "circular"
    faces = np.nonzero(bad)[0]
    if len(faces):
        name = fixed if isinstance(fixed, str) else f"{len(fixed_idx)} listed vertices"
        worst = measures.planarity(mesh)[faces] if what == "planar" else None
        detail = f" (planarity up to {worst.max():.3g}, tolerance {tol.planarity:g})" if worst is not None else ""
        raise ConfigError(f"fixed: {name!r} fixes every vertex of {len(faces)} face(s) that are not "
                          f"{what}{detail}: faces {faces[:10].tolist()}; no iteration can change them, "
                          f"so {target} cannot be reached; fix fewer vertices (e.g. 'corners') or glide")


def _held(res: OptimizeResult, norm: Mesh, Xn: np.ndarray, keep: Convex, tol: Tolerances) -> None:
    """``defects["convexity"]``: the faces whose corners sit at their convexity floor while the
    face is not yet planar (where no fold-free mesh is near); a run that missed its tolerance
    says so, naming them."""
    s = convexity.sines(norm, Xn, keep.corners)
    at = s < keep.floor + 1e-3 * np.maximum(keep.floor, 1e-9) + 1e-9
    faces = np.unique(norm.topology.corner_face[keep.corners[at]])
    planar = measures.planarity(norm, Xn)
    held = faces[planar[faces] > tol.planarity]
    held = held[np.argsort(-planar[held])]
    res.defects["convexity"] = {"at_floor": len(faces), "held": len(held),
                                "faces": held[:20].tolist(), "sine_floor": convexity.SINE_FLOOR}
    if res.status != "converged" and len(held):
        bad = np.nonzero(planar > tol.planarity)[0]
        bad = bad[np.argsort(-planar[bad])]
        net = res.defects.get("net", {})
        what = "PQ" if res.target == "pq" else res.target
        res.message += (f"; the default solver found no fold-free {what} mesh near the input: {len(bad)} face(s) "
                        f"stay non-planar (worst first: {bad[:6].tolist()}, up to {planar[bad[0]]:.2g}) where "
                        f"planar faces would dent {len(held)} face(s) held at the convexity floor "
                        f"({held[:6].tolist()}); {net.get('line', '')}; {HELD_ADVICE}")


def _unit(U: np.ndarray) -> np.ndarray:
    return U / np.maximum(np.linalg.norm(U, axis=1, keepdims=True), 1e-300)


def _node_axes(form: Formulation, x: np.ndarray, normals: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unit axes ``(n, 3)`` and cone angles ``(n,)``: the solved ones where the formulation has
    axis unknowns, elsewhere the node axes fitted to the final unit face normals ``normals (m, 3)``
    (:func:`optimize.mesh.axes.fit_axes`, the offset stage's fit)."""
    fit = fit_axes(form.mesh, normals)
    axes, cosines = fit.axes.copy(), fit.cos_theta.copy()
    cv = form.cone_vertices
    if "axes" in form.layout:
        a = form.layout.view(x, "axes")
        axes[cv] = _unit(a)
        cosines[cv] = form.layout.view(x, "cos") / np.linalg.norm(a, axis=1)
    av = form.axis_vertices
    if len(av):  # solved node axes (torsion-free beams), every vertex
        a = form.layout.view(x, "node_axes")
        axes[av] = _unit(a)
        cosines[av] = form.layout.view(x, "node_cos") / np.linalg.norm(a, axis=1)
    return axes, np.arccos(np.clip(cosines, -1.0, 1.0))


def _paper(mesh, target, **kwargs) -> OptimizeResult:
    """Dispatch to ``optimize.solvers.paper.run_paper_method`` (teammate H3), imported lazily."""
    try:
        from .solvers import paper
    except ImportError as exc:
        raise ConfigError(f"method: {kwargs['method']!r} needs optimize.solvers.paper (the paper's penalty "
                          f"and SQP methods), which is not available: {exc}") from exc
    return paper.run_paper_method(mesh, target, **kwargs)


def _group(norm: Mesh, fixed_idx: np.ndarray) -> symmetry.Group:
    """The input's rigid symmetries (:func:`optimize.mesh.symmetry.detect`) that map the fixed
    vertices onto fixed vertices (a subgroup: the others cannot be kept with them fixed)."""
    group = symmetry.detect(norm)
    if group.trivial or not len(fixed_idx):
        return group
    pinned = np.zeros(norm.n_vertices, dtype=bool)
    pinned[fixed_idx] = True
    return symmetry.Group(tuple(g for g in group.maps if pinned[g.perm[fixed_idx]].all()), group.tol)


def _keep_symmetry(form: Formulation, run, group: symmetry.Group, glide, keep, tol: Tolerances, backend: str,
                   callback) -> tuple:
    """The run's iterate projected onto the input's symmetries (``group``, normalized coordinates):
    the group average of its vertices; when that leaves a defect over its tolerance, a guided solve
    from there without the closeness term (whose footpoints are not symmetric; every other row is
    equivariant, so the solve stays symmetric to rounding) and the average again.  Kept when every
    defect is within tolerance and no face folds; otherwise the run stands and the record says so.
    Returns the run and a JSON-ready record (deviations over the mean edge length)."""
    L = form.layout
    V = L.view(run.x, "vertices")
    rec = {"order": group.order, "kinds": group.kinds(), "deviation": group.deviation(V), "kept": False,
           "iterations": 0}
    if run.status != "converged":
        rec["note"] = f"the solve ended {run.status}: left as it is"
        return run, rec

    def averaged(x):
        y = x.copy()
        L.view(y, "vertices")[:] = group.symmetrize(L.view(x, "vertices"))
        return y

    folds = convexity.FoldCheck(form.mesh, keep.V0 if keep is not None else V.copy(), tol.fold)
    x = averaged(run.x)
    nit, history = 0, []
    if guided._score(guided.measured(form, x, glide), tol) > 0:
        again = solve(form, x, ref=None, glide=glide, tol=tol, max_iter=50, callback=callback, backend=backend,
                      convex=keep, far=guided.FAR)
        nit, history = again.nit, [dict(e, phase="symmetry", iteration=run.nit + e["iteration"]) for e in again.history]
        x = averaged(again.x)
    defects = guided.measured(form, x, glide)
    ok = guided._score(defects, tol) <= 0 and not folds.faces(L.view(x, "vertices")).any()
    rec.update(iterations=nit, result_deviation=group.deviation(L.view(x, "vertices")), kept=bool(ok))
    if not ok:
        rec["note"] = "the symmetric projection missed a tolerance or folded a face: the solve's result stands"
        return run, rec
    timings = dict(run.timings)
    return guided.RunState(x=x, status="converged", message=run.message, nit=run.nit + nit,
                           history=run.history + history, timings=timings,
                           defects={k: float(d.max(initial=0.0)) for k, d in defects.items()}), rec
