"""One problem description that every solver reads: unknowns, terms, energies.

A :class:`ProblemSpec` is frozen and says, for one run of one method on one
mesh and target, everything that is decided before the first iteration:

- the unknowns' :class:`~optimize.terms.variables.Layout` (named slices) and the
  index sets its blocks and terms are counted on (``sets``: cone vertices, circle
  quads, n-gons, vertices with node-axis unknowns, gliding vertices and edges);
- the normalization the unknowns live in: ``x_vertices = (V - centre) / scale``,
  ``scale`` the mean edge length (:func:`optimize.mesh.measures.normalization`);
- the fixed vertices (removed from the unknowns);
- the terms (:class:`TermSpec`: name, term module, kind, weight, options), in
  the order their rows are stacked;
- the energies (:class:`Energies`: fairness and closeness weights, the reference);
- the defects that must reach tolerance (``tests``).

:func:`describe` is the one place that decides, per target and method, which
terms run.  The two families of methods legitimately choose different rows
for the same target:

=========  ====================================================================
method     terms (kind)
=========  ====================================================================
default    least squares, every row at most quadratic (``unknowns="auxiliary"``):
           planarity on unit face normals, cone axes (conical), circle centres
           (circular); or on positions only (``"vertices"``): the diagonals, the
           angle balance, the opposite-angle sums, node axes and planar beams;
           then boundary gliding, its edge floors, convexity (when asked for)
penalty    least squares, weighted: the paper's angle sum per face, angle balance
           (conical), opposite-angle pairs (circular), strip determinants (``mu``)
sqp        constraints: the same, with the determinants' alternating mean
           instead of the quads' angle sums (:func:`_paper_constraints`)
hybrid     both lists: the penalty phase reads the least-squares rows, SQP the
           constraints
=========  ====================================================================

The default method's rows are evaluated by :class:`optimize.terms.formulation.Formulation`
(``solvers.guided``), the paper's on fixed patterns by
:class:`optimize.solvers.paper.problem.Problem` (``solvers.paper``); both are
built from a description and neither chooses terms itself.
"""
from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

import numpy as np

from ..errors import ConfigError, MeshError
from ..mesh import Mesh, measures
from ..options import DEFAULT_TARGETS, METHODS, TARGETS
from . import circular, nodeaxes
from . import fixed as fixed_mod
from .variables import Layout

KINDS = ("constraint", "least_squares", "energy")
UNKNOWNS = ("auxiliary", "vertices")
GLIDE_EDGE_FLOOR = 0.5  # with a gliding boundary, no boundary edge below half its start length


def _frozen(d: dict | None = None) -> Mapping:
    return MappingProxyType(dict(d or {}))


@dataclass(frozen=True)
class TermSpec:
    """One block of rows of a problem.

    name : str, the block's name (the paper's methods key histories and multipliers by it).
    module : str, the term module under :mod:`optimize.terms` that writes the rows.
    kind : one of ``KINDS``: ``"constraint"`` (an equality constraint, SQP),
        ``"least_squares"`` (a residual row of the least-squares objective, penalty and
        default) or ``"energy"``.
    weight : float, the block's weight (the paper's ``mu`` for determinants).
    options : read-only mapping of the module's options: ``block`` (the unknowns' block
        name), ``faces`` / ``vertices`` (a name in ``ProblemSpec.sets``), ``rows``
        (``"first"``: one opposite-angle row per quad), ``form`` (determinants:
        ``"four"`` per quad or their alternating ``"mean"``), ``part`` (node axes:
        ``"cone"`` or ``"beam"``), ``split`` (may enter as per-face parts).
    """

    name: str
    module: str
    kind: str
    weight: float = 1.0
    options: Mapping[str, Any] = field(default_factory=_frozen)

    def __post_init__(self):
        if self.kind not in KINDS:
            raise ValueError(f"TermSpec {self.name!r}: kind {self.kind!r}, expected one of {KINDS}")
        object.__setattr__(self, "options", _frozen(self.options))


@dataclass(frozen=True)
class Energies:
    """The soft terms: weights ``fairness``, ``closeness`` (relative to the rows, in
    normalized coordinates) and the ``reference`` surface of closeness (None: the input)."""

    fairness: float
    closeness: float
    reference: Mesh | None = None


@dataclass(frozen=True, eq=False)
class ProblemSpec:
    """The description of one run (module docstring).

    mesh : Mesh, the input (never modified).  target, method : str.
    unknowns : ``"auxiliary"`` or ``"vertices"`` (the paper's methods: ``"vertices"``).
    layout : Layout of the unknown vector (do not modify).
    centre : (3,) float, scale : float: ``x_vertices = (V - centre) / scale``.
    fixed : (k,) int sorted vertices that do not move.
    sets : read-only ``name -> (p,) int`` index sets the blocks and terms run on.
    terms : tuple of TermSpec in row order.  energies : Energies.
    tests : names of the measured defects that must reach tolerance.
    """

    mesh: Mesh
    target: str
    method: str
    unknowns: str
    layout: Layout
    centre: np.ndarray
    scale: float
    fixed: np.ndarray
    sets: Mapping[str, np.ndarray]
    terms: tuple[TermSpec, ...]
    energies: Energies
    tests: tuple[str, ...]

    def rows(self, kind: str) -> tuple[TermSpec, ...]:
        """The terms of ``kind``, in row order."""
        return tuple(t for t in self.terms if t.kind == kind)

    def normalized(self) -> Mesh:
        """The input mesh in the unknowns' coordinates (same faces and topology)."""
        return self.mesh.with_vertices((self.mesh.V - self.centre) / self.scale)


def resolve_formulation(target: str, formulation: str) -> str:
    """The unknowns ``"auto"`` stands for: positions only for ``conical`` (3x smaller
    factors, fewer iterations; see ``optimize.terms.formulation``), auxiliary otherwise."""
    if formulation != "auto":
        return formulation
    return "vertices" if target == "conical" else "auxiliary"


def default_mu(mesh: Mesh, target: str, method: str) -> float:
    """The determinant weight a paper's method uses when none is given.

    The paper: ``mu = 1`` for strips, 0 otherwise, for the penalty method.
    SQP and hybrid add the determinant rows on every quad mesh (``mu = 1``):
    the angle rows are degenerate at planar faces (their gradients vanish),
    so a linearized constraint cannot see planarity and a Newton-KKT step
    cannot converge to a planar mesh from them alone (measured: with
    ``mu = 0`` SQP stalls at planarity 1e-4 .. 1e-3 on a perturbed surface
    of revolution).
    """
    if target == "strip":
        return 1.0
    return 1.0 if method in ("sqp", "hybrid") and np.any(mesh.face_sizes == 4) else 0.0


def tested_defects(target: str, mu: float | None = None) -> tuple[str, ...]:
    """Names of the measured defects that must reach tolerance for ``target``."""
    extra = {"pq": (), "conical": ("conical",), "circular": ("circular",), "strip": ("det",)}[target]
    if mu is not None and mu > 0 and "det" not in extra:
        extra = extra + ("det",)
    return ("planarity",) + extra


def check_strip(mesh: Mesh) -> None:
    """Raise :class:`MeshError` unless ``mesh`` is one connected row of quads.

    Every face must be a quad sharing at most two edges, opposite ones, with
    other faces, and every vertex must lie on the boundary.
    """
    t = mesh.topology
    if not mesh.is_quad:
        raise MeshError(f"{mesh.name}: target 'strip' needs quads only, found face sizes "
                        f"{sorted(set(mesh.face_sizes.tolist()))}")
    if t.n_components != 1:
        raise MeshError(f"{mesh.name}: target 'strip' needs one connected row of quads, "
                        f"found {t.n_components} components")
    inner = ~t.is_boundary_edge[t.corner_edge].reshape(-1, 4)  # (m, 4): slot j shared
    count = inner.sum(axis=1)
    opposite = (inner[:, 0] & inner[:, 2]) | (inner[:, 1] & inner[:, 3])
    bad = (count > 2) | ((count == 2) & ~opposite)
    if bad.any():
        f = int(np.argmax(bad))
        raise MeshError(f"{mesh.name}: target 'strip' needs a single row of quads; face {f} shares "
                        f"{int(count[f])} edges with other faces, expected at most two opposite ones")
    if not t.is_boundary_vertex.all():
        v = int(np.argmin(t.is_boundary_vertex))
        raise MeshError(f"{mesh.name}: target 'strip' needs a single row of quads; vertex {v} is "
                        "interior, expected every vertex on the boundary")


def describe(mesh: Mesh, target: str, method: str = "default", *, formulation: str = "auxiliary",
             beams=False, fixed=None, glide_boundary: bool = False, convex: bool = False, fairness: float = 0.0,
             closeness: float = 0.0, reference: Mesh | None = None, mu: float | None = None) -> ProblemSpec:
    """The :class:`ProblemSpec` of ``method`` for ``target`` on ``mesh``.

    formulation : ``"auxiliary"`` | ``"vertices"`` | ``"auto"`` (default method only).
    beams : torsion-free beams (default method, conical with the vertex formulation):
        True | False | ``"auto"`` (when the mesh has interior vertices of valence other than 4).
    fixed : None | "none" | "boundary" | "corners" | (k,) int (:func:`optimize.terms.fixed.resolve`);
        with ``glide_boundary`` (default method) the corner vertices are fixed too.
    glide_boundary : (default method) the free boundary vertices glide on the reference's
        boundary curve (``sets["glide"]``, term ``glide``), and the boundary edges at them keep
        ``GLIDE_EDGE_FLOOR`` of their start length (``sets["glide_edges"]``, term ``edge_floor``).
    convex : (default method) convex corners stay convex (term ``convexity``).
    fairness, closeness, reference : the energies.
    mu : the paper's determinant weight (None: :func:`default_mu` of ``method``).
    Raises :class:`ConfigError` for an unknown method, target, formulation or fixed value,
    negative weights, or determinant rows on a mesh without quads; :class:`MeshError` for
    target ``strip`` on a mesh that is not one row of quads.
    """
    if method not in METHODS:
        raise ConfigError(f"method: {method!r} is not known, expected one of {METHODS}")
    if method == "default":
        return _describe_default(mesh, target, formulation, beams, fixed, glide_boundary, convex,
                                 Energies(float(fairness), float(closeness), reference))
    return _describe_paper(mesh, target, method, fixed, fairness, closeness, reference, mu)


def _common(mesh: Mesh, fixed, glide_boundary: bool) -> tuple[np.ndarray, float, np.ndarray]:
    centre, scale = measures.normalization(mesh)
    fixed_idx = fixed_mod.resolve(mesh, fixed)
    if glide_boundary:  # corners stay: a point cannot glide around a kink of the curve
        fixed_idx = np.union1d(fixed_idx, fixed_mod.corner_vertices(mesh))
    return centre, scale, fixed_idx


def _describe_default(mesh: Mesh, target: str, formulation: str, beams, fixed, glide_boundary: bool,
                      convex: bool, energies: Energies) -> ProblemSpec:
    """The default method's rows (module docstring; ``optimize.terms.formulation``)."""
    if target not in DEFAULT_TARGETS:
        raise ConfigError(f"target: {target!r} is not known, expected one of {DEFAULT_TARGETS}")
    unknowns = resolve_formulation(target, formulation)
    if unknowns not in UNKNOWNS:
        raise ConfigError(f"formulation: {unknowns!r} is not known, expected one of {UNKNOWNS}")
    t = mesh.topology
    if beams == "auto":
        beams = bool(t.interior_irregular.size)
    beams = bool(beams) and target == "conical" and unknowns == "vertices"
    centre, scale, fixed_idx = _common(mesh, fixed, glide_boundary)
    empty = np.zeros(0, dtype=np.int64)
    sets = {"cone_vertices": t.interior_valence4 if target == "conical" else np.zeros(0, int),
            "quads": circular.circle_faces(mesh) if target == "circular" else np.zeros(0, int),
            "ngons": empty, "axis_vertices": empty}
    L = Layout().add("vertices", mesh.n_vertices, 3)
    ls = "least_squares"
    terms = []
    if unknowns == "vertices":
        sets["ngons"] = np.nonzero(mesh.face_sizes > 4)[0]
        terms.append(TermSpec("diagonals", "diagonals", ls))
        if len(sets["ngons"]):  # a unit normal per n-gon (see terms.diagonals)
            L.add("ngon_normals", len(sets["ngons"]), 3)
            terms += [TermSpec("ngon_planarity", "planarity", ls, options={"faces": "ngons", "block": "ngon_normals"}),
                      TermSpec("ngon_unit", "unit", ls, options={"block": "ngon_normals"})]
        if target == "conical" and len(sets["cone_vertices"]):
            terms.append(TermSpec("balance", "anglebalance", ls))
        if target == "circular" and len(sets["quads"]):
            terms.append(TermSpec("circular", "anglesum", ls))
        if beams:  # node axes as unknowns, planar beams (terms.nodeaxes)
            sets["axis_vertices"] = nodeaxes.axis_vertices(mesh)
            p = len(sets["axis_vertices"])
            L.add("node_axes", p, 3).add("node_cos", p, 1)
        if len(sets["axis_vertices"]):
            terms += [TermSpec("node_cone", "nodeaxes", ls, options={"part": "cone"}),
                      TermSpec("node_axes_unit", "unit", ls, options={"block": "node_axes"}),
                      TermSpec("beam", "nodeaxes", ls, options={"part": "beam"})]
    else:
        L.add("normals", mesh.n_faces, 3)
        terms += [TermSpec("planarity", "planarity", ls, options={"block": "normals"}),
                  TermSpec("normals_unit", "unit", ls, options={"block": "normals"})]
        if target == "conical":
            p = len(sets["cone_vertices"])
            L.add("axes", p, 3).add("cos", p, 1)
            terms += [TermSpec("conical", "conical", ls), TermSpec("axes_unit", "unit", ls, options={"block": "axes"}),
                      TermSpec("balance", "anglebalance", ls, options={"split": True})]
        if target == "circular":
            L.add("centres", len(sets["quads"]), 3).add("radius2", len(sets["quads"]), 1)
            terms += [TermSpec("circles", "circular", ls), TermSpec("circular", "anglesum", ls)]
    if glide_boundary:  # the solver carries the curve and the floors (solvers.guided.Glide)
        bnd = np.setdiff1d(np.nonzero(t.is_boundary_vertex)[0], fixed_idx)
        if bnd.size:
            E = t.edges
            at = t.is_boundary_edge & np.isin(E, bnd).any(1)  # a gliding vertex cannot slide onto its neighbour
            sets["glide"], sets["glide_edges"] = bnd, E[at]
            terms.append(TermSpec("glide", "glide", ls))
            if at.any():
                terms.append(TermSpec("edge_floor", "edgefloor", ls, options={"floor": GLIDE_EDGE_FLOOR}))
    if convex:  # the solver carries the floors (solvers.guided.Convex)
        terms.append(TermSpec("convexity", "convexity", ls))
    terms += [TermSpec("fairness", "fairness", "energy", energies.fairness),
              TermSpec("closeness", "closeness", "energy", energies.closeness)]
    return ProblemSpec(mesh, target, "default", unknowns, L, centre, scale, fixed_idx, _frozen(sets),
                       tuple(terms), energies, tested_defects(target))


def _describe_paper(mesh: Mesh, target: str, method: str, fixed, fairness, closeness, reference,
                    mu: float | None) -> ProblemSpec:
    """The paper's rows (section 2.2 and section 3; ``optimize.solvers.paper.targets``)."""
    if target not in TARGETS:
        raise ConfigError(f"target {target!r} is not known to the paper's methods, expected one of {TARGETS}")
    if target == "strip":
        check_strip(mesh)
    mu = default_mu(mesh, target, method) if mu is None else float(mu)
    sizes = mesh.face_sizes
    sets = {"ngons": np.nonzero(sizes > 4)[0]}
    ls = "least_squares"
    rows = []
    if target == "circular":
        rows.append(TermSpec("circular", "anglesum", ls))
        if sets["ngons"].size:
            rows.append(TermSpec("angle_sum", "facesum", ls, options={"faces": "ngons"}))
    else:
        rows.append(TermSpec("angle_sum", "facesum", ls))
    if target == "conical":
        rows.append(TermSpec("balance", "anglebalance", ls))
    if mu > 0:
        if not np.any(sizes == 4):
            raise ConfigError(f"mu = {mu}: determinant terms need quads, {mesh.name} has none")
        rows.append(TermSpec("det", "determinants", ls, weight=mu, options={"form": "four"}))
    w_fair, w_close = float(fairness), float(closeness)
    if w_fair < 0 or w_close < 0:
        raise ConfigError(f"fairness={fairness}, closeness={closeness}: weights must be >= 0")
    terms = []
    if method in ("penalty", "hybrid"):
        terms += rows
    if method in ("sqp", "hybrid"):
        terms += _paper_constraints(rows, bool(sets["ngons"].size))
    energies = Energies(w_fair, w_close, reference)
    terms += [TermSpec("fairness", "fairness", "energy", w_fair), TermSpec("closeness", "closeness", "energy", w_close)]
    centre, scale, fixed_idx = _common(mesh, fixed, False)
    return ProblemSpec(mesh, target, method, "vertices", Layout.vertices_only(mesh.n_vertices), centre, scale,
                       fixed_idx, _frozen(sets), tuple(terms), energies, tested_defects(target, mu))


def _paper_constraints(rows: list[TermSpec], ngons: bool) -> list[TermSpec]:
    """The rows SQP imposes as equality constraints, from the penalty rows ``rows``.

    With determinant rows present, planarity of the quads is expressed by one
    row per quad, the alternating mean of the four determinants, and the
    quads' angle sums are left out.  The determinant's gradient does not
    vanish at a planar quad, the angle sum's does; a row whose gradient
    vanishes at the solution (or four rows of rank one) leaves the KKT
    conditions without (unique) multipliers, and SQP's multipliers then grow
    without bound.  For the same reason only the first circular row of each
    quad (``phi1 + phi3 = pi``) is kept: at a planar quad the two rows add up
    to the angle sum, so their gradients are opposite; with planarity and
    convexity the first implies the second.  Angle sums of n-gons (n > 4) and
    the conical balance stay.
    """
    def constraint(t: TermSpec, **options) -> TermSpec:
        return TermSpec(t.name, t.module, "constraint", t.weight, {**t.options, **options})

    if not any(t.module == "determinants" for t in rows):
        return [constraint(t) for t in rows]
    out = []
    for t in rows:
        if t.module == "determinants":
            out.append(constraint(t, form="mean"))
        elif t.module == "anglesum":
            out.append(constraint(t, rows="first"))
        elif t.name != "angle_sum":
            out.append(constraint(t))
        elif ngons:
            out.append(TermSpec("angle_sum", "facesum", "constraint", t.weight, {"faces": "ngons"}))
    return out
