"""The offset stage: from a (conical) mesh to layers, node axes and beams.

``offset_structure(mesh, distances)`` is a pure function: the mesh comes in,
an immutable :class:`OffsetStructure` with every array and a JSON-ready
report comes out.  It never refuses a mesh that is merely imperfect: a PQ
mesh that is not conical, or (when the caller allows it) a mesh that is not
even PQ, gets least-squares axes and a report that says so and by how much.
:func:`require_pq` is the check a caller runs first to refuse non-PQ input.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from optimize.errors import ConfigError, MeshError
from optimize.mesh.measures import conical_defect, planarity
from optimize.mesh import Mesh
from optimize.tolerances import Tolerances

from .axes import check_orientable, face_planes, fit_axes, given_axes
from .beams import beam_normals, beam_quads, beam_twist
from .layers import face_distance_errors, offset_layers
from .report import offset_report
from .straighten import straighten_free_axes

FREE_AXES = ("planar_beams", "min_norm")


@dataclass(frozen=True)
class OffsetStructure:
    """Layers, node axes and beams of a mesh (model units, mm in fabrication).

    mesh : the input Mesh (``n`` vertices, ``m`` faces, ``e`` edges)
    distances : tuple of ``L`` signed offset distances, as given
    normals : (m, 3) unit face normals (flipped when asked)
    axes : (n, 3) unit node axes, on the normals' side
    cos_theta : (n,) cosine of the cone angle, > 0
    axis_defect : (n,) radians, half the spread of the face angles about the axis
    is_conical : PQ and conical within ``tol.conical`` (:func:`conical_everywhere`)
    layers : ``L`` arrays (n, 3), ``V + d * axes / cos_theta``, same vertex order
    edges : (e, 2) vertex pairs (``mesh.topology.edges``)
    beam_quads : (e, 4, 3) ``[v_a@d0, v_b@d0, v_b@d1, v_a@d1]`` between ``beam_span``
    beam_normals : (e, 3) unit beam-plane normals
    beam_twist_mm : (e,) distance between the beam quad's diagonals
    beam_twist_deg : (e,) signed twist angle about the edge
    face_distance_error : (m, L) max corner deviation of each offset face from ``d``
    report : JSON-ready dict, worst elements named (see :mod:`fabricate.offset.report`)
    beam_span : (d0, d1), the first and last distance (``(0, d)`` for one distance)
    face_distance_spread : (m, L) how far each offset face is from parallel
    planarity : (m,) planarity of the input faces
    offset : (n, 3) offset vectors ``axes / cos_theta``
    flip : whether the face normals were reversed
    """

    mesh: Mesh
    distances: tuple
    normals: np.ndarray
    axes: np.ndarray
    cos_theta: np.ndarray
    axis_defect: np.ndarray
    is_conical: bool
    layers: tuple
    edges: np.ndarray
    beam_quads: np.ndarray
    beam_normals: np.ndarray
    beam_twist_mm: np.ndarray
    beam_twist_deg: np.ndarray
    face_distance_error: np.ndarray
    report: dict = field(repr=False)
    beam_span: tuple = (0.0, 0.0)
    face_distance_spread: np.ndarray | None = None
    planarity: np.ndarray | None = None
    offset: np.ndarray | None = None
    flip: bool = False

    def layer_mesh(self, i: int) -> Mesh:
        """Layer ``i`` as a Mesh with the input's faces and topology."""
        d = self.distances[i]
        return self.mesh.with_vertices(self.layers[i], name=f"{self.mesh.name}_layer_{d:g}")

    def beam_mesh(self) -> Mesh:
        """The beam quads as one Mesh of ``e`` separate quads (``4 e`` vertices), for writing."""
        e = len(self.edges)
        F = np.arange(4 * e, dtype=np.int64).reshape(e, 4)
        return Mesh(self.beam_quads.reshape(-1, 3), F, name=f"{self.mesh.name}_beams", check=False)


def require_pq(mesh: Mesh, tol: Tolerances = Tolerances(), worst: int = 5) -> None:
    """Raise :class:`MeshError` naming the worst faces when ``mesh`` is not PQ within ``tol.planarity``."""
    p = planarity(mesh)
    bad = np.nonzero(p > tol.planarity)[0]
    if bad.size == 0:
        return
    top = bad[np.argsort(-p[bad])][:worst]
    named = ", ".join(f"face {int(f)} {mesh.F[f][mesh.F[f] >= 0].tolist()}: {p[f]:.3g}" for f in top)
    raise MeshError(f"{mesh.name}: {bad.size} of {mesh.n_faces} faces are not planar (planarity above "
                    f"{tol.planarity:g}; worst {named}), expected a PQ mesh: optimize it first "
                    "(target pq or conical) or force the offset and read the report")


def conical_everywhere(mesh: Mesh, axis_defect: np.ndarray, tol: Tolerances) -> bool:
    """Conical by the shared definition: angle balance ``|w1 + w3 - w2 - w4| <= tol.conical`` at
    interior valence-4 vertices, and ``axis_defect (n,) <= tol.conical`` at other interior vertices."""
    t = mesh.topology
    other = ~t.is_boundary_vertex
    other[t.interior_valence4] = False
    return bool(conical_defect(mesh).max(initial=0.0) <= tol.conical
                and axis_defect[other].max(initial=0.0) <= tol.conical)


def _distances(distances) -> tuple[float, ...]:
    try:
        ds = tuple(float(d) for d in np.atleast_1d(np.asarray(distances, dtype=object)))
    except (TypeError, ValueError) as exc:
        raise ConfigError(f"offset distances {distances!r}: {exc}, expected numbers (mm)") from None
    if not ds:
        raise ConfigError("offset distances: none given, expected at least one distance (mm)")
    for d in ds:
        if not math.isfinite(d):
            raise ConfigError(f"offset distances {list(ds)}: {d} is not finite, expected numbers (mm)")
    if len(set(ds)) != len(ds):
        twice = next(d for d in ds if ds.count(d) > 1)
        raise ConfigError(f"offset distances {list(ds)}: {twice:g} is given twice, "
                          "expected distinct distances")
    if ds == (0.0,):
        raise ConfigError("offset distances [0]: a single zero distance gives no layer and no beams, "
                          "expected a non-zero distance")
    return ds


def offset_structure(mesh: Mesh, distances, *, axes=None, flip: bool = False,
                     tol: Tolerances = Tolerances(), free_axes: str = "planar_beams") -> OffsetStructure:
    """Offset layers, node axes and beams of ``mesh``.

    Parameters
    ----------
    mesh : Mesh, orientable; faces oriented by their order (``flip`` reverses)
    distances : sequence of ``L`` distinct signed distances (mm), e.g. ``(0, 20, 120)``
    axes : (n, 3) float or None, node axes to use (e.g. the optimizer's
        ``result.axes``); rows that are NaN or zero are fitted (and, with
        ``free_axes="planar_beams"``, turned like fitted axes); given rows are kept
    flip : reverse the face normals (layers go to the other side)
    tol : tolerances quoted and checked in the report
    free_axes : ``"planar_beams"`` (default) turns the axes that the faces leave
        free (boundary vertices, cylinder-like vertices) so that their beams are
        planar; ``"min_norm"`` keeps the bisector axes

    Raises MeshError (not orientable, bad ``axes``) and ConfigError (bad distances).
    """
    if free_axes not in FREE_AXES:
        raise ConfigError(f"free_axes={free_axes!r}, expected one of {FREE_AXES}")
    check_orientable(mesh)
    ds = _distances(distances)
    normals, _ = face_planes(mesh, flip)
    edges = mesh.topology.edges.copy()
    straighten = None
    fit = fit_axes(mesh, normals) if axes is None else given_axes(mesh, normals, axes)
    if free_axes == "planar_beams":  # only the axes the faces leave free are turned
        fit, straighten = straighten_free_axes(mesh.V, edges, fit)
    layers = offset_layers(mesh.V, fit.offset, ds)
    span = (ds[0], ds[-1]) if len(ds) > 1 else (0.0, ds[0])
    lo, hi = (mesh.V + span[0] * fit.offset, mesh.V + span[1] * fit.offset)
    Q = beam_quads(edges, lo, hi)
    twist_mm, twist_deg = beam_twist(Q)
    err, spread = face_distance_errors(mesh, normals, layers, ds)
    plan = planarity(mesh)
    is_pq = bool(plan.max() <= tol.planarity)
    is_conical = bool(is_pq and conical_everywhere(mesh, fit.defect, tol))
    arrays = dict(normals=normals, axes=fit.axes, cos_theta=fit.cos_theta, axis_defect=fit.defect,
                  edges=edges, beam_quads=Q, beam_normals=beam_normals(Q), beam_twist_mm=twist_mm,
                  beam_twist_deg=twist_deg, face_distance_error=err, face_distance_spread=spread,
                  planarity=plan, offset=fit.offset)
    for a in arrays.values():
        a.setflags(write=False)
    layers = tuple(x for x in layers)
    for x in layers:
        x.setflags(write=False)
    report = offset_report(mesh, ds, span, arrays, tol=tol, is_pq=is_pq, is_conical=is_conical,
                           flip=flip, axes_source="given" if axes is not None else free_axes,
                           straighten=straighten)
    return OffsetStructure(mesh=mesh, distances=ds, is_conical=is_conical, layers=layers, report=report,
                           beam_span=span, flip=bool(flip), **arrays)
