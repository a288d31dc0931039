"""The beam network as a 3D frame: nodes, elements, local axes, sections, supports (mm, N, MPa).

:class:`Frame` is engine-neutral data: :func:`fabricate.structure.engine.solve` hands it to
OpenSees.  :func:`frame_from_offset` builds it from the offset stage: one node per mesh vertex
on its node axis (at the depth of the section's centroid between the first and the last layer),
one element per beam (mesh edge), local ``z`` along the beam-plane normal so that the local
``y`` axis (the section depth) lies in the beam plane: the strong axis bends in the plane.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from optimize.errors import ConfigError, MeshError

from .sections import SectionProperties


@dataclass(frozen=True, eq=False)
class Frame:
    """A linear-elastic 3D frame.

    X : (n, 3) float node coordinates, mm.
    elements : (e, 2) int node pairs.
    vecxz : (e, 3) float, a vector in each element's local x-z plane (here the beam-plane normal).
    sections : tuple of SectionProperties; section_of : (e,) int index into it.
    E, G : elastic and shear modulus, MPa.
    fixed : (n, 6) bool restrained dofs (ux uy uz rx ry rz).
    pinned : moments released at both ends of every element (pinned connections).
    ids : (e,) str element names (beam part ids); node_ids : (n,) str.
    top : (e,) float, +1 where the element's local ``y`` points to the section's top fibre (the glass
        side), -1 where it points away; None when unknown (the section class then takes both signs).
    springs : (n, 6) float or None: support springs, N/mm (translations) and N mm/rad (rotations), on
        dofs that are not ``fixed`` (0: free); the reaction of a spring is its force.
    joint_stiffness : N mm/rad, semi-rigid joints: every element end is joined to its node by a
        rotational spring of this stiffness about both bending axes (0: rigid; ``pinned`` overrides).
    """

    X: np.ndarray
    elements: np.ndarray
    vecxz: np.ndarray
    sections: tuple
    section_of: np.ndarray
    E: float
    G: float
    fixed: np.ndarray
    pinned: bool = False
    ids: tuple = ()
    node_ids: tuple = ()
    top: np.ndarray | None = None
    springs: np.ndarray | None = None
    joint_stiffness: float = 0.0

    @property
    def semi_rigid(self) -> bool:
        return (not self.pinned) and self.joint_stiffness > 0

    def supported(self) -> np.ndarray:
        """(n,) bool nodes held by a fixed dof or a spring."""
        held = self.fixed.any(axis=1)
        return held | (self.springs > 0).any(axis=1) if self.springs is not None else held

    @property
    def n_nodes(self) -> int:
        return int(len(self.X))

    @property
    def n_elements(self) -> int:
        return int(len(self.elements))

    def lengths(self) -> np.ndarray:
        """(e,) float element lengths, mm."""
        return np.linalg.norm(self.X[self.elements[:, 1]] - self.X[self.elements[:, 0]], axis=1)

    def local_axes(self) -> np.ndarray:
        """(e, 3, 3) float rows ``x, y, z`` of each element's local frame (OpenSees' convention:
        ``y = vecxz x x``, ``z = x x y``)."""
        d = self.X[self.elements[:, 1]] - self.X[self.elements[:, 0]]
        x = d / np.linalg.norm(d, axis=1, keepdims=True)
        y = np.cross(self.vecxz, x)
        y /= np.linalg.norm(y, axis=1, keepdims=True)
        return np.stack([x, y, np.cross(x, y)], axis=1)

    def prop(self, name: str) -> np.ndarray:
        """(e,) float section property ``name`` (``A``, ``Iy``, ``Wz``, ...) of every element."""
        values = np.array([getattr(s, name) for s in self.sections], dtype=float)
        return values[self.section_of]

    def with_sections(self, sections, section_of) -> "Frame":
        """The same frame with other sections (``section_of (e,)`` into ``sections``)."""
        return replace(self, sections=tuple(sections), section_of=np.asarray(section_of, dtype=np.int64))

    def steel_mass_kg(self, density: float = 7850.0) -> float:
        """Total mass of the elements' sections over their lengths (kg)."""
        return float(np.sum(self.prop("A") * self.lengths()) * 1e-9 * density)


def check_frame(frame: Frame) -> None:
    """Raise MeshError / ConfigError for a frame no engine can solve (zero-length or aligned
    elements, no support)."""
    L = frame.lengths()
    if frame.n_elements == 0:
        raise MeshError("structure: the mesh has no edges, so no beams to check")
    short = np.nonzero(~(L > 1e-9 * max(float(L.max()), 1.0)))[0]
    if short.size:
        raise MeshError(f"structure: beam {frame.ids[short[0]] if frame.ids else short[0]} has zero length "
                        f"({short.size} such beams), expected distinct nodes")
    d = (frame.X[frame.elements[:, 1]] - frame.X[frame.elements[:, 0]]) / L[:, None]
    cz = np.linalg.norm(np.cross(frame.vecxz, d), axis=1) / np.linalg.norm(frame.vecxz, axis=1)
    bad = np.nonzero(~(cz > 1e-9))[0]
    if bad.size:
        raise MeshError(f"structure: beam {frame.ids[bad[0]] if frame.ids else bad[0]}: its beam-plane normal is "
                        "parallel to the beam, expected a normal across it")
    if not frame.supported().any():
        raise ConfigError("structure.supports: no node is supported, expected at least one support")


LOWEST_FRACTION = 0.05
"""``supports: lowest`` without a tolerance: vertices within this fraction of the height above the lowest."""


def support_vertices(V: np.ndarray, boundary: np.ndarray, supports, tolerance: float | None, up,
                     loops=()) -> np.ndarray:
    """Vertex indices chosen by ``structure.supports``.

    V : (n, 3) float mm; boundary : (n,) bool boundary vertices.
    supports : ``"lowest"`` (vertices within ``tolerance`` mm above the lowest one along ``up``,
        default :data:`LOWEST_FRACTION` of the height, on the boundary when the mesh has one),
        ``"boundary"``, ``"outline"`` (the longest boundary loop: a roof's edge without the rims of
        its openings; ``loops`` the mesh's boundary loops) or a list of vertex indices.
    """
    n = len(V)
    if isinstance(supports, str) and supports == "boundary":
        sel = np.nonzero(boundary)[0]
        if sel.size == 0:
            raise ConfigError("structure.supports = 'boundary': the mesh has no boundary (closed), expected "
                              "'lowest' or vertex indices")
        return sel
    if isinstance(supports, str) and supports == "outline":
        if not len(loops):
            raise ConfigError("structure.supports = 'outline': the mesh has no boundary (closed), expected "
                              "'lowest' or vertex indices")
        lengths = [float(np.linalg.norm(V[np.roll(lp, -1)] - V[lp], axis=1).sum()) for lp in loops]
        return np.unique(np.asarray(loops[int(np.argmax(lengths))]))
    if isinstance(supports, str) and supports == "lowest":
        u = np.asarray(up, dtype=float) / np.linalg.norm(up)
        h = V @ u
        pool = boundary if boundary.any() else np.ones(n, bool)
        low = h[pool].min()
        if tolerance is None:
            tolerance = LOWEST_FRACTION * float(h.max() - h.min())
        return np.nonzero(pool & (h <= low + tolerance))[0]
    idx = np.asarray(list(supports), dtype=np.int64)
    if idx.size and (idx.max() >= n):
        bad = int(idx[idx >= n][0])
        raise ConfigError(f"structure.supports: vertex {bad} does not exist, expected indices 0..{n - 1}")
    return np.unique(idx)


def frame_from_offset(structure, section: SectionProperties, *, E: float, G: float, supports="lowest",
                      support_tolerance: float | None = None, support_kind: str = "pinned", pinned: bool = False,
                      up=(0.0, 0.0, 1.0)) -> tuple[Frame, np.ndarray]:
    """The frame of an :class:`fabricate.offset.OffsetStructure` with one ``section`` everywhere.

    Returns ``(frame, support_vertices (k,) int)``.  Nodes are ``V + d * offset`` with ``d`` at
    the section's centroid between the first and the last layer (``beam_span``).
    """
    from fabricate.cad.parts import part_ids

    mesh = structure.mesh
    d0, d1 = structure.beam_span
    frac = section.centroid / section.h
    X = np.asarray(mesh.V + (d0 + frac * (d1 - d0)) * structure.offset, dtype=float)
    edges = np.asarray(structure.edges, dtype=np.int64)
    sup = support_vertices(np.asarray(mesh.V), mesh.topology.is_boundary_vertex, supports, support_tolerance, up,
                           loops=mesh.topology.boundary_loops)
    if sup.size == 0:
        raise ConfigError(f"structure.supports = {supports!r}: selects no vertex, expected at least one support")
    fixed = np.zeros((len(X), 6), dtype=bool)
    fixed[sup, :3] = True
    if support_kind == "fixed":
        fixed[sup, 3:] = True
    frame = Frame(X=X, elements=edges, vecxz=np.asarray(structure.beam_normals, dtype=float), sections=(section,),
                  section_of=np.zeros(len(edges), dtype=np.int64), E=float(E), G=float(G), fixed=fixed,
                  pinned=bool(pinned), ids=part_ids("beam", np.arange(len(edges))),
                  node_ids=part_ids("node", np.arange(len(X))))
    check_frame(frame)
    # the top fibre lies toward the first layer (the glass): (d0 - d1) along the node axes
    up_axis = (d0 - d1) * (np.asarray(structure.offset, dtype=float)[edges[:, 0]]
                           + np.asarray(structure.offset, dtype=float)[edges[:, 1]])
    y = frame.local_axes()[:, 1]
    return replace(frame, top=np.where(np.einsum("ei,ei->e", y, up_axis) >= 0, 1.0, -1.0)), sup
