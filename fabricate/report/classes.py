"""``classes.png``: the glass units on the roof coloured by their shape (#37 item 3).

Every glass unit is drawn where it sits, filled with the colour of its congruence class (the glass
schedule's type, :func:`fabricate.export.schedules.glass_types`, the rule ``report.json``'s
``totals.glass_shapes`` counts by): a shape made two or more times gets a colour of its own (the
largest classes first), a shape made once is light grey; the other hand of a shape made in both is
hatched.  The legend names the largest classes with their counts.  A rationalized run
(``optimize.rationalize``) is drawn after its rationalization, the title saying how many shapes
there were before.

The roof is drawn in plan when the panels face up (their plan area at least half their area), else
in an oblique view (far faces first); one :class:`~matplotlib.collections.PolyCollection` per fill,
so that the picture stays cheap on thousands of panels.  The counts are written into the PNG's
``Description`` text as well (``glass shapes: 36; ...``), for a reader or a test to check against
``report.json``.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from optimize.atomic import atomic_path
from optimize.errors import writing

SINGLE = (0.86, 0.86, 0.86, 1.0)
"""Fill of a shape made once (light grey)."""
LEGEND_CLASSES = 12
"""Classes named in the legend at most (the largest); the rest are counted in one line."""
PLAN_SHARE = 0.5
"""The roof is drawn in plan when the panels' plan area is at least this share of their area."""
VIEW = (28.0, -58.0)
"""Elevation and azimuth (degrees) of the oblique view (as the 3D pictures of :mod:`.pictures`)."""


def class_drawing(parts, mesh) -> dict:
    """What :func:`picture_classes` draws: ``polygons`` (u, (k, 3)) every glass unit's mesh face (mm),
    ``label`` (u,) its shape class, ``hand`` (u,) 1 for the other hand of a shape made in both,
    ``names`` (c,) the classes' type names (``G001``), ``counts`` (c,) their sizes, ``tolerance_mm``."""
    from fabricate.cad.glass import bearing_groups
    from fabricate.export.schedules import TYPE_PREFIX, glass_types

    _, names, c = glass_types(parts)
    units = bearing_groups(parts)
    element = np.concatenate([g.element for g in units]) if units else np.zeros(0, dtype=np.int64)
    sizes = mesh.face_sizes
    polygons = [mesh.V[mesh.F[f, :sizes[f]]] for f in element.tolist()]
    label = np.asarray(c.label, dtype=np.int64)
    both = c.handed
    hand = np.where(both[label], c.hand, 0) if len(label) else np.zeros(0, dtype=np.int64)
    first = [names[i] for i in np.asarray(c.first, dtype=np.int64).tolist()]
    prefix = TYPE_PREFIX["glass"]
    return {"polygons": polygons, "label": label, "hand": hand,
            "names": [n.rstrip("AB") if n.startswith(prefix) else n for n in first],
            "counts": np.bincount(label, minlength=c.count), "tolerance_mm": c.tol}


def class_counts(drawing: dict) -> dict:
    """``{"panels", "shapes", "repeated", "singletons", "largest"}`` of a :func:`class_drawing`:
    the shapes (classes), those made twice or more, those made once, the largest class's size."""
    counts = np.asarray(drawing["counts"])
    return {"panels": int(counts.sum()), "shapes": int(len(counts)), "repeated": int((counts >= 2).sum()),
            "singletons": int((counts == 1).sum()), "largest": int(counts.max()) if len(counts) else 0}


def palette(n: int) -> np.ndarray:
    """(n, 4) RGBA colours, as distinct as they come: tab20, tab20b, tab20c, then golden-ratio hues."""
    from matplotlib import colormaps
    from matplotlib.colors import hsv_to_rgb

    base = np.concatenate([colormaps[m](np.arange(20)) for m in ("tab20", "tab20b", "tab20c")])
    base = base[[i for i in range(len(base)) if not np.allclose(base[i, :3], base[i, 0], atol=0.02)]]  # no greys
    if n <= len(base):
        return base[:n]
    k = np.arange(n - len(base))
    hsv = np.stack([(k * 0.618034) % 1.0, 0.55 + 0.35 * (k % 3) / 2, 0.95 - 0.25 * (k % 2)], axis=1)
    extra = np.concatenate([hsv_to_rgb(hsv), np.ones((len(k), 1))], axis=1)
    return np.concatenate([base, extra])


def _projection(polygons: list[np.ndarray]) -> tuple[list[np.ndarray], np.ndarray, str]:
    """The polygons in 2D, the order to draw them (far first) and the view's name."""
    if not polygons:
        return [], np.zeros(0, dtype=np.int64), "plan"

    def area(P):  # (3,) vector area of a polygon
        return 0.5 * np.cross(P, np.roll(P, -1, axis=0)).sum(axis=0)

    A = np.array([area(P) for P in polygons])
    if np.abs(A[:, 2]).sum() >= PLAN_SHARE * np.linalg.norm(A, axis=1).sum():
        return [P[:, :2] for P in polygons], np.argsort([P[:, 2].mean() for P in polygons], kind="stable"), "plan"
    el, az = np.radians(VIEW)
    right = np.array([-np.sin(az), np.cos(az), 0.0])
    toward = np.array([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])
    up = np.cross(toward, right)
    flat = [np.stack([P @ right, P @ up], axis=1) for P in polygons]
    return flat, np.argsort([P.mean(axis=0) @ toward for P in polygons], kind="stable"), "oblique view"


def picture_classes(drawing: dict, path: str | Path, *, title: str) -> dict:
    """Draw ``drawing`` (:func:`class_drawing`) to ``path``; returns :func:`class_counts` and ``view``."""
    from matplotlib.collections import PolyCollection
    from matplotlib.patches import Patch

    from .pictures import DPI, _figure

    counts = class_counts(drawing)
    label, hand, sizes = drawing["label"], drawing["hand"], np.asarray(drawing["counts"])
    flat, order, view = _projection(drawing["polygons"])
    rank = np.argsort(-sizes, kind="stable")                       # the largest classes first
    repeated = rank[sizes[rank] >= 2]
    colour = np.tile(np.array(SINGLE), (len(sizes), 1))
    colour[repeated] = palette(len(repeated))
    fig = _figure((7.5, 6.0))
    ax = fig.add_subplot(111)
    for h, hatch in ((0, None), (1, "////")):  # one collection per fill: the other hand hatched
        sel = order[hand[order] == h]
        if len(sel):
            ax.add_collection(PolyCollection([flat[i] for i in sel.tolist()], facecolors=colour[label[sel]],
                                             edgecolors=(0.25, 0.25, 0.25, 0.8), linewidths=0.3, hatch=hatch))
    if flat:
        allp = np.concatenate(flat)
        lo, hi = allp.min(axis=0), allp.max(axis=0)
        pad = 0.03 * float(max(np.ptp(allp, axis=0).max(), 1.0))
        ax.set_xlim(lo[0] - pad, hi[0] + pad)
        ax.set_ylim(lo[1] - pad, hi[1] + pad)
    ax.set_aspect("equal")
    ax.set_axis_off()
    names = drawing["names"]
    handles = [Patch(facecolor=colour[c], edgecolor="0.3", label=f"{names[c]}: {sizes[c]} panels")
               for c in repeated[:LEGEND_CLASSES].tolist()]
    rest = repeated[LEGEND_CLASSES:]
    if len(rest):
        handles.append(Patch(facecolor="white", edgecolor="white",
                             label=f"{len(rest)} more shapes of 2+: {int(sizes[rest].sum())} panels"))
    if counts["singletons"]:
        handles.append(Patch(facecolor=SINGLE, edgecolor="0.3", label=f"{counts['singletons']} shapes made once"))
    if hand.any():
        handles.append(Patch(facecolor="white", edgecolor="0.3", hatch="////", label="the other hand (mirror image)"))
    if handles:
        ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=7, frameon=False,
                  title=f"{counts['shapes']} shapes", title_fontsize=8)
    ax.set_title(title, fontsize=10)
    text = (f"glass shapes: {counts['shapes']}; panels: {counts['panels']}; shapes of 2+: {counts['repeated']}; "
            f"made once: {counts['singletons']}; tolerance_mm: {drawing['tolerance_mm']:g}; view: {view}")
    path = Path(path)
    with writing(path, "picture"), atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", dpi=DPI, bbox_inches="tight", metadata={"Description": text})
    return dict(counts, view=view)


def classes_picture(run, parts) -> dict[str, str]:
    """``classes.png`` of ``run`` (RunRecord) and its caption (``{}`` without glass units)."""
    drawing = class_drawing(parts, parts.mesh if parts.mesh is not None else run.optimize.mesh)
    if not len(drawing["label"]):
        return {}
    n = class_counts(drawing)
    tol = drawing["tolerance_mm"]
    title = f"{run.config.name}: {n['panels']:,} glass units in {n['shapes']:,} shapes (within {tol:g} mm)"
    result = run.optimize.result
    rat = (result.defects or {}).get("rationalize") if result is not None else None
    before = ""
    if isinstance(rat, dict) and rat.get("before") and rat.get("pull") is not None:
        before = (f"rationalized (pull {rat['pull']:g} mm): mesh faces of {rat['before']['shapes']:,} shapes "
                  f"before, {rat['after']['shapes']:,} after")
        title += "\n" + before
    facts = picture_classes(drawing, run.workdir / "classes.png", title=title)
    caption = (f"the glass units coloured by shape ({facts['view']}): {n['shapes']:,} shapes within {tol:g} mm, "
               f"{n['repeated']:,} of them made twice or more (in colour), {n['singletons']:,} made once (grey)"
               + (f"; {before}" if before else ""))
    return {"classes.png": caption}
