"""Beam sections welded from flat plates: plate, tee, I and rectangular hollow (RHS).

Every plate is a convex planar-faced hexahedron cut from flat stock, bounded
by six of the planes :func:`fabricate.cad.beams.beam_solids` computes (so
flat data, nesting, STEP and the checks work per plate, exactly):

- ``plate``: one plate (the beam of :mod:`fabricate.cad.beams`), ``beam_width`` thick.
- ``tee``: that plate as the web (``web_mm``), and a top flange on the glass
  side as two half-flange plates beside the web, each in the plane of the
  glass panel on its side (the ridge planes ``T0+`` / ``T0-``), so the glass
  bears flush on web and flanges; their undersides parallel, ``flange_mm``
  below; their outer edges in planes parallel to the beam plane at
  ``flange_width_mm / 2`` (so the width across the beam plane is the nominal
  one; the edge is bevelled by the panel's tilt, written in the flat data).
- ``i``: the tee and a bottom flange the same way in the ``T1+`` / ``T1-`` planes.
- ``rhs``: a welded box: two webs parallel to the beam plane, symmetric about
  it, their outside faces at ``flange_width_mm / 2``; top and bottom flanges as
  two halves each (in ``T0+-`` / ``T1+-``), meeting on the beam plane (the weld
  along the ridge) and covering the webs.

The webs stay in (or parallel to) the beam plane, so every beam is as
torsion-free as its quad.  Every plate on the ``+`` side of the beam plane is
cut by the ``+`` side end planes (``Ea+``, ``Eb+``), every plate on the ``-``
side by the ``-`` ones: the bisector planes through the node axis at mitred
ends (a neighbour's plates are cut by the same plane from the other side, so
they never overlap), the square ends of a hub set back for the flange width.

Box plate layout (vertices, faces) shared by every flange and RHS web::

    0..3  the reference face (outline, CCW seen from outside), 4..7 behind it
    faces: ref (0 1 2 3), back (4 7 6 5), side 0 (0 4 5 1), side 2 (2 6 7 3), end (1 5 6 2), end (0 3 7 4)

Ring edge 0 (``0 -> 1``) runs along the beam on the inner / upper side
(the weld edge of a flange, the top edge of a web), edges 1 and 3 are the end
cuts (:data:`BOX_FACES`; which end is ``a`` is :func:`box_plates`' ``end_faces``).
"""
from __future__ import annotations

import numpy as np

from .geometry import meet3, volumes

BOX_FACES = ((0, 1, 2, 3), (4, 7, 6, 5), (0, 4, 5, 1), (2, 6, 7, 3), (1, 5, 6, 2), (0, 3, 7, 4))
BOX_RING = (0, 1, 2, 3)
BOX_NAMES = ("reference", "back", "side 0", "side 2", "end", "end")
MEMBERS = {
    "plate": ("",),
    "tee": ("web", "top flange +", "top flange -"),
    "i": ("web", "top flange +", "top flange -", "bottom flange +", "bottom flange -"),
    "rhs": ("web +", "web -", "top flange +", "top flange -", "bottom flange +", "bottom flange -"),
}
"""The plates of each section, in id order (``B0001.1`` is the first)."""


def _flip(pl):
    return -pl[0], -pl[1]


def _shift(pl, d):
    """The plane moved ``d`` against its outward normal (into the part)."""
    return pl[0], pl[1] - d


def box_plates(ref, back, side0, side2, end_a, end_b) -> dict:
    """Vertices ``(e, 8, 3)`` and outward normals ``(e, 6, 3)`` of hexahedral plates from six planes.

    Every argument is ``(normal (e, 3), offset (e,))``, outward.  The reference face's corners are
    ``ref & side0 & end_a``, ``ref & side0 & end_b``, ``ref & side2 & end_b``, ``ref & side2 & end_a``
    when that turns counter-clockwise about ``ref``; else ``end_a`` and ``end_b`` trade places (a
    mirrored plate).  Returns also ``end_faces (2,)``: the faces at end ``a`` and ``b``.
    """
    def corners(ea, eb):
        X = np.empty(ref[0].shape[:1] + (8, 3))
        for k, (face, side, end) in enumerate(((ref, side0, ea), (ref, side0, eb), (ref, side2, eb),
                                                (ref, side2, ea), (back, side0, ea), (back, side0, eb),
                                                (back, side2, eb), (back, side2, ea))):
            X[:, k], _ = meet3(face[0], face[1], side[0], side[1], end[0], end[1])
        return X

    X = corners(end_a, end_b)
    mirrored = bool(np.median(volumes(X, BOX_FACES)) < 0) if len(X) else False
    if mirrored:
        X = corners(end_b, end_a)
    first, second = (end_b, end_a) if mirrored else (end_a, end_b)
    normals = np.stack([ref[0], back[0], side0[0], side2[0], second[0], first[0]], axis=1)
    return {"vertices": X, "normals": normals, "end_faces": np.array([4, 5] if mirrored else [5, 4])}


def flange_plates(planes: dict, section: str, web: float, flange: float, width: float) -> list[dict]:
    """The plates of a section besides the plate web: ``[{"member", "vertices", "normals", "end_faces"}]``.

    planes : :func:`fabricate.cad.beams.beam_solids`' ``planes`` (built with the web thickness
    ``web`` for ``tee`` / ``i``); web, flange, width : mm (``rhs``: each web, each flange, outside width).
    """
    P = planes
    n, off = P["mid"]
    B = 0.5 * width
    out = []

    def add(member, *args):
        out.append(dict(box_plates(*args), member=member))

    if section in ("tee", "i"):
        rows = [("top", "T0")] + ([("bottom", "T1")] if section == "i" else [])
        for where, T in rows:
            for s, sign in (("+", 1.0), ("-", -1.0)):
                ridge = P[T + s]
                inner = _flip(P["F" + s])
                outer = (sign * n, sign * off + B)
                add(f"{where} flange {s}", ridge, _flip(_shift(ridge, flange)), inner, outer,
                    P["Ea" + s], P["Eb" + s])
    elif section == "rhs":
        for s, sign in (("+", 1.0), ("-", -1.0)):
            outer = (sign * n, sign * off + B)
            add(f"web {s}", outer, (-sign * n, -(sign * off + B - web)), _shift(P["T0" + s], flange),
                _shift(P["T1" + s], flange), P["Ea" + s], P["Eb" + s])
        for where, T in (("top", "T0"), ("bottom", "T1")):
            for s, sign in (("+", 1.0), ("-", -1.0)):
                ridge = P[T + s]
                add(f"{where} flange {s}", ridge, _flip(_shift(ridge, flange)), (-sign * n, -sign * off),
                    (sign * n, sign * off + B), P["Ea" + s], P["Eb" + s])
    elif section != "plate":
        raise ValueError(f"section {section!r}: expected plate, tee, i or rhs")
    return out


def section_text(spec, depth: float) -> str:
    """What the steel shop reads: ``RHS 200x100x8`` (h x b x t; ``x8/12`` web / flange when they differ),
    ``T 200x120x10/12``, ``I 200x120x10/12`` (h x b x web / flange), ``plate 60 x 200``; mm."""
    b = spec.beam
    h = f"{depth:.0f}"
    if b.section == "plate":
        return f"plate {spec.beam_width:g} x {h}"
    tw, tf, w = spec.web, b.flange_mm, b.flange_width_mm
    if b.section == "rhs":
        wall = f"{tw:g}" if tw == tf else f"{tw:g}/{tf:g}"
        return f"RHS {h}x{w:g}x{wall}"
    return f"{'T' if b.section == 'tee' else 'I'} {h}x{w:g}x{tw:g}/{tf:g}"


def section_rectangles(spec, depth: float) -> list[tuple[float, float, float, float]]:
    """The nominal cross-section as its plates' rectangles ``(y0, y1, z0, z1)`` in mm (``y`` across the
    beam plane, ``z`` down from the glass bearing, flat flanges: a 180 degree dihedral).

    The plate and the tee / I web span the whole depth beside the flanges; an RHS's flanges span its
    width and its webs the depth between them.
    """
    b = spec.beam
    if b.section == "plate":
        w = spec.beam_width
        return [(-w / 2, w / 2, 0.0, depth)]
    tw, tf, B = spec.web, b.flange_mm, b.flange_width_mm / 2
    if b.section == "rhs":
        return [(B - tw, B, tf, depth - tf), (-B, -B + tw, tf, depth - tf), (0.0, B, 0.0, tf), (-B, 0.0, 0.0, tf),
                (0.0, B, depth - tf, depth), (-B, 0.0, depth - tf, depth)]
    rects = [(-tw / 2, tw / 2, 0.0, depth), (tw / 2, B, 0.0, tf), (-B, -tw / 2, 0.0, tf)]
    if b.section == "i":
        rects += [(tw / 2, B, depth - tf, depth), (-B, -tw / 2, depth - tf, depth)]
    return rects
