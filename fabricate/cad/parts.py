"""Parts as pure data: planar-faced solids with stable ids, no CAD kernel needed.

A :class:`PartGroup` holds ``p`` solids of one combinatorial type (all beams;
all panels with ``k`` sides; all nodes), so that exporters and checks work on
whole arrays.  :class:`Part` is one solid seen through its group (a light
view, made on demand).  :class:`Parts` is what ``build_parts`` returns.

Ids are ``P0001`` (panel of mesh face 0), ``B0001`` (beam of topology edge 0),
``N0001`` (node of vertex 0): the number is the element index + 1, so an id
never changes when other parts are added or options change, and the same id
names the solid in STEP, STL/3MF, DXF/SVG and the bill of materials.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from typing import Any, Iterator

import numpy as np

KINDS = ("panel", "beam", "node")
PREFIX = {"panel": "P", "beam": "B", "node": "N"}
COLOURS = {"panel": (0.55, 0.78, 0.90), "beam": (0.45, 0.47, 0.50), "node": (0.80, 0.45, 0.15)}
"""RGB (0..1) of each kind, used by STEP, 3MF and SVG."""


def part_ids(kind: str, element: np.ndarray) -> tuple[str, ...]:
    """Ids ``P0001 ...`` for element indices ``(p,)`` (at least 4 digits, more when needed)."""
    width = max(4, len(str(int(element.max()) + 1))) if len(element) else 4
    return tuple(f"{PREFIX[kind]}{int(i) + 1:0{width}d}" for i in element)


GENUS = {"tube": 1}
"""Holes through a part by its ``member`` (a hub tube has one); every other part is genus 0."""


SHEET_MEMBERS = {"panel": None, "beam": None, "node": ("top cap", "bottom cap")}
"""Which solids are cut from sheet, by kind: every panel and beam solid (None), of the nodes only a
tube hub's cap plates (the tube is ordered as a hollow section, a solid hub is turned)."""


def cut_from_sheet(kind: str, member: str) -> bool:
    """Whether a solid of ``kind`` and ``member`` is cut from sheet (has flat data in ``flat.json`` and
    the cut files); takes a :class:`PartGroup`'s or a BOM row's ``kind`` and ``member``."""
    if kind not in SHEET_MEMBERS:
        return False
    members = SHEET_MEMBERS[kind]
    return members is None or member in members


def unit_id(part_id: str) -> str:
    """The unit a solid belongs to: ``P0001.2`` -> ``P0001``; a one-solid part is its own unit."""
    return part_id.split(".", 1)[0]


@dataclass(frozen=True, eq=False)
class PartGroup:
    """``p`` planar-faced solids of one kind and one combinatorial type.

    kind : ``panel`` | ``beam`` | ``node``.
    ids : (p,) str.  element : (p,) int mesh face / edge / vertex index.
    vertices : (p, nv, 3) float, mm.
    faces : tuple of vertex-index tuples, outward (counter-clockwise seen from
        outside), shared by every solid of the group; every face is convex.
    normals : (p, nf, 3) float, outward unit normal of every face (the plane
        each face was built in).
    volume_mm3 : (p,) analytic volume (divergence theorem on the same polygons).
    outline_face : index of the face drawn flat (panels: the face bearing on
        the beams; beams: the face on their ``+`` side; nodes: the cap).
    bevel_face : index of the parallel opposite face (drawn as a second
        outline in the plane of the first), or -1.
    flat : (p, k, 2) float, mm: the true outline the shop cuts (panel: the face
        bearing on the beams; beam: its full profile with the V ends reaching the
        node axes and the ridge under the glass), in the part frame of
        :mod:`fabricate.cad.flat`: rotated so its smallest bounding rectangle is
        axis-aligned (a rigid motion: exact edge lengths), seen from outside
        (counter-clockwise).
    flat_bevel : (p, k2, 2) float or None: the bevel line drawn dashed (panel: the opposite
        face; beam: its ``+`` plate face, where the bevels of the ``+`` side end).
    rect : (p, 2) float: width >= height of a rectangle (axis-aligned in the flat frame)
        that holds every vertex of the part: the stock it is cut from.
    bevel_ref : (p, k, 2) float: the line each edge's bevels are measured from (panel: the
        bearing face; beam: its ridges and V tips), edge ``j`` of it under edge ``j`` of ``flat``.
    bevel_ref_z : (p, k) float: height of each of its corners in the part frame (the sheet
        is ``-thickness <= z <= 0``; panels 0, beams about ``-thickness / 2``).
    bevel_deg : (p, k, 2) float: per edge, the cut face's angle from square on the ``+z`` and
        ``-z`` side, positive when the part narrows toward that face (:mod:`fabricate.cad.flat`).
    transform : (p, 4, 4) float: part frame -> model (mm), rigid.
    flat_faces : the two sheet faces ``((p, kt, 2), (p, kb, 2))`` in the part frame.
    cuts : (k, 2) int: the face cut along each outline edge [+z side, -z side].
    ring : the vertices of ``bevel_ref`` (panel: the bearing face; beam: its centre line).
    area_mm2, length_mm, thickness_mm : (p,) float: outline area, length along
        the part (0 for panels), thickness across the outline plane.
    planarity_mm : (p,) float: how far the source polygon (mesh face at the
        glass layer, beam quad) was from the plane the part was built in.
    residual_mm : (p,) float: largest distance of a vertex from the planes of
        its faces after construction (round-off; what OpenCASCADE sees).
    neighbours : (p,) tuple of id tuples: parts in contact (panel: its beams
        and nodes; beam: its panels, the beams it meets at its nodes, nodes).
    member : ``""`` for a part that is one solid.  A part built of several solids
        (a laminated or insulated glass unit, a beam welded from plates) is
        several groups, one per member, each naming what it is in the unit
        (``"ply 1"``, ``"web"``, ``"top flange +"``); their ids are
        ``<unit id>.<k>`` (``P0001.1``, ``B0012.3``, k from 1), see :func:`unit_id`.
    centre_line : (p, 4, 3) float or None: beams: the beam quad ``A0 B0 B1 A1`` (corners on the
        node axes) of the beam each plate belongs to, the same for every member of a unit.
    material : ``""`` for the kind's material (panel glass, beam and node steel), else what the
        solids are made of (a glass unit's interlayer: ``PVB``, ``SGP``); see ``PartSpec.group_density``.
    """

    kind: str
    ids: tuple[str, ...]
    element: np.ndarray
    vertices: np.ndarray
    faces: tuple[tuple[int, ...], ...]
    normals: np.ndarray
    volume_mm3: np.ndarray
    outline_face: int
    bevel_face: int
    flat: np.ndarray
    flat_bevel: np.ndarray | None
    rect: np.ndarray
    bevel_ref: np.ndarray
    bevel_ref_z: np.ndarray
    bevel_deg: np.ndarray
    transform: np.ndarray
    flat_faces: tuple
    cuts: np.ndarray
    ring: tuple[int, ...]
    area_mm2: np.ndarray
    length_mm: np.ndarray
    thickness_mm: np.ndarray
    planarity_mm: np.ndarray
    residual_mm: np.ndarray
    neighbours: tuple[tuple[str, ...], ...]
    member: str = ""
    centre_line: np.ndarray | None = None
    material: str = ""

    def __len__(self) -> int:
        return len(self.ids)

    def part(self, i: int) -> "Part":
        return Part(self, i)


@dataclass(frozen=True, eq=False)
class Part:
    """One solid of a :class:`PartGroup` (attributes read through to the group)."""

    group: PartGroup
    index: int

    @property
    def id(self) -> str:
        return self.group.ids[self.index]

    @property
    def kind(self) -> str:
        return self.group.kind

    @property
    def element(self) -> int:
        return int(self.group.element[self.index])

    @property
    def vertices(self) -> np.ndarray:
        """(nv, 3) float, mm."""
        return self.group.vertices[self.index]

    @property
    def faces(self) -> tuple[tuple[int, ...], ...]:
        return self.group.faces

    @property
    def polygons(self) -> list[np.ndarray]:
        """Every face as a ``(k, 3)`` array, outward orientation."""
        V = self.vertices
        return [V[list(f)] for f in self.group.faces]

    def __getattr__(self, name: str) -> Any:
        if name in ("volume_mm3", "area_mm2", "length_mm", "thickness_mm", "planarity_mm", "residual_mm"):
            return float(getattr(self.group, name)[self.index])
        if name in ("flat", "rect", "normals", "neighbours", "bevel_ref", "bevel_ref_z", "bevel_deg", "transform"):
            return getattr(self.group, name)[self.index]
        raise AttributeError(name)

    def __repr__(self) -> str:
        return f"Part({self.id}, {self.kind}, element {self.element}, {self.volume_mm3:.6g} mm3)"


@dataclass(frozen=True, eq=False)
class Parts:
    """Every solid of a structure, grouped by kind and type.

    groups : tuple of :class:`PartGroup` (panels first, then beams, then nodes).
    spec : the :class:`fabricate.cad.PartSpec` used.
    edge_mode : ``axis`` or ``perpendicular`` (``auto`` resolved).
    report : dict, JSON-ready: counts, volumes, masses, worst planarity, ...
    mesh : the mesh the parts were built on (element indices refer to it).
    """

    groups: tuple[PartGroup, ...]
    spec: Any
    edge_mode: str
    report: dict = field(default_factory=dict)
    mesh: Any = None

    def of_kind(self, kind: str) -> list[PartGroup]:
        return [g for g in self.groups if g.kind == kind]

    def _list(self, kind: str) -> list[Part]:
        return [g.part(i) for g in self.of_kind(kind) for i in range(len(g))]

    @cached_property
    def panels(self) -> list[Part]:
        return self._list("panel")

    @cached_property
    def beams(self) -> list[Part]:
        return self._list("beam")

    @cached_property
    def nodes(self) -> list[Part]:
        return self._list("node")

    def __len__(self) -> int:
        return sum(len(g) for g in self.groups)

    def __iter__(self) -> Iterator[Part]:
        for kind in KINDS:
            yield from getattr(self, kind + "s")

    @cached_property
    def by_id(self) -> dict[str, Part]:
        return {p.id: p for p in self}

    def bounds(self) -> np.ndarray:
        """(2, 3) float: min and max corner of every vertex of every part (mm)."""
        lo = np.min([g.vertices.reshape(-1, 3).min(axis=0) for g in self.groups], axis=0)
        hi = np.max([g.vertices.reshape(-1, 3).max(axis=0) for g in self.groups], axis=0)
        return np.stack([lo, hi])

    def to_build123d(self, kinds=KINDS):
        """A labelled build123d assembly to continue modelling with: a ``Compound`` labelled ``model``
        with one child ``Compound`` per kind (``panels``, ``beams``, ``nodes``) holding one
        ``Solid`` per part, labelled with its id and coloured by kind (the same exact B-rep solids
        as ``model.step``: one plane per face, shared edges)."""
        from build123d import Color, Compound, Solid

        from fabricate.export.brep import group_solids

        children = []
        for kind in kinds:
            solids = []
            for g in self.of_kind(kind):
                for pid, shape in zip(g.ids, group_solids(g)):  # one wrapper per part
                    solid = Solid(shape)
                    solid.label, solid.color = pid, Color(*COLOURS[kind])
                    solids.append(solid)
            if solids:
                children.append(Compound(label=kind + "s", children=solids))
        return Compound(label="model", children=children)

    def local_origin(self) -> np.ndarray:
        """(3,) float: an offset that brings a far-from-origin model near the origin.

        Zero when the model's bounding box centre is within one bounding-box
        diagonal of the origin; otherwise the centre rounded to whole metres.
        Float32 writers (STL, manifold3d) subtract it and record it.
        """
        lo, hi = self.bounds()
        centre, diag = 0.5 * (lo + hi), float(np.linalg.norm(hi - lo))
        if np.linalg.norm(centre) <= max(diag, 1.0):
            return np.zeros(3)
        return np.round(centre / 1000.0) * 1000.0
