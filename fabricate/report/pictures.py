"""Pictures of a run, rendered headless (matplotlib's Agg canvas, no pyplot state).

Each function draws one PNG from plain arrays and writes it atomically:

- :func:`picture_defect`: the design with faces (or vertices) coloured by a
  defect on a log scale, the tolerance marked on the colour bar;
- :func:`picture_layers`: the offset layers as wireframes with the beams;
- :func:`picture_history`: defects against iteration (log scale) with tolerances;
- the shop drawings (nested sheets, layout plan) are in :mod:`.shop_pictures`; the ids
  on them are sized by :func:`outline_label_sizes` and drawn by :func:`_id_patch`.

The figure objects are created without ``pyplot`` so that threads (a Dask
worker) can draw at the same time.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from optimize.atomic import atomic_path
from optimize.errors import writing
from optimize.mesh import Mesh

DPI = 110
FLOOR = 1e-17


def _figure(size=(7.0, 5.5)):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=size, dpi=DPI)
    FigureCanvasAgg(fig)
    return fig


def _save(fig, path: str | Path) -> Path:
    path = Path(path)
    with writing(path, "picture"), atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", dpi=DPI, bbox_inches="tight")
    return path


def face_polygons(mesh: Mesh) -> list[np.ndarray]:
    """Faces as ``(k, 3)`` arrays (one gather per face size)."""
    sizes = mesh.face_sizes
    polys: list[np.ndarray | None] = [None] * mesh.n_faces
    for k in np.unique(sizes):
        idx = np.nonzero(sizes == k)[0]
        for i, P in zip(idx, mesh.V[mesh.F[idx, :k]]):
            polys[i] = P
    return polys  # type: ignore[return-value]


def _axes3d(fig, V: np.ndarray, rect=111):
    ax = fig.add_subplot(rect, projection="3d")
    lo, hi = V.min(axis=0), V.max(axis=0)
    span = np.maximum(hi - lo, 1e-9 * max(float(np.ptp(V)), 1.0))
    ax.set_xlim(lo[0], lo[0] + span[0])
    ax.set_ylim(lo[1], lo[1] + span[1])
    ax.set_zlim(lo[2], lo[2] + span[2])
    ax.set_box_aspect(span / span.max())
    ax.view_init(elev=28, azim=-58)
    ax.set_axis_off()
    return ax


def _lognorm(values: np.ndarray, tolerance: float | None):
    from matplotlib.colors import LogNorm

    v = np.maximum(np.asarray(values, dtype=float), FLOOR)
    hi = max(float(v.max()), (tolerance or FLOOR) * 10)
    lo = min(float(v.min()), (tolerance or hi) / 100)
    lo = min(max(lo, FLOOR), hi / 10)
    return LogNorm(vmin=lo, vmax=hi), v


def picture_defect(mesh: Mesh, values: np.ndarray, path: str | Path, *, title: str, label: str,
                   tolerance: float | None = None, vertices: np.ndarray | None = None) -> Path:
    """The design coloured by a defect on a log scale.

    values : (m,) per face, or (p,) per vertex when ``vertices`` (p,) int are given
        (then faces are drawn grey and the vertices as coloured dots).
    """
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    fig = _figure()
    ax = _axes3d(fig, mesh.V)
    cmap = "viridis"
    norm, v = _lognorm(values if len(values) else np.array([FLOOR]), tolerance)
    polys = face_polygons(mesh)
    if vertices is None:
        from matplotlib import colormaps

        colors = colormaps[cmap](norm(v))
        ax.add_collection3d(Poly3DCollection(polys, facecolors=colors, edgecolors=(0.2, 0.2, 0.2, 0.6),
                                             linewidths=0.3))
    else:
        ax.add_collection3d(Poly3DCollection(polys, facecolors=(0.85, 0.87, 0.9, 0.5),
                                             edgecolors=(0.3, 0.3, 0.3, 0.5), linewidths=0.3))
        if len(vertices):
            P = mesh.V[np.asarray(vertices, dtype=np.int64)]
            ax.scatter(P[:, 0], P[:, 1], P[:, 2], c=v, cmap=cmap, norm=norm, s=14, depthshade=False)
    from matplotlib.cm import ScalarMappable

    bar = fig.colorbar(ScalarMappable(norm=norm, cmap=cmap), ax=ax, shrink=0.7, pad=0.02)
    bar.set_label(label + ("  (red line: tolerance)" if tolerance is not None else ""))
    if tolerance is not None:
        bar.ax.axhline(tolerance, color="red", linewidth=2)
    worst = float(np.max(values)) if len(values) else 0.0
    ok = "" if tolerance is None else ("  (within tolerance)" if worst <= tolerance else "  (NOT within tolerance)")
    ax.set_title(f"{title}\nmax {worst:.3g}{ok}", fontsize=10)
    return _save(fig, path)


def picture_layers(layers: list[np.ndarray], edges: np.ndarray, beam_quads: np.ndarray, path: str | Path,
                   *, title: str, distances: tuple[float, ...] = ()) -> Path:
    """The offset layers (wireframes, one colour each) with the beams (grey quads).

    layers : list of (n, 3) vertex arrays, same vertex order; edges : (e, 2) int;
    beam_quads : (e, 4, 3).
    """
    from mpl_toolkits.mplot3d.art3d import Line3DCollection, Poly3DCollection

    fig = _figure()
    ax = _axes3d(fig, np.concatenate([np.asarray(L) for L in layers], axis=0))
    if len(beam_quads):
        ax.add_collection3d(Poly3DCollection(list(np.asarray(beam_quads)), facecolors=(0.55, 0.57, 0.6, 0.55),
                                             edgecolors=(0.35, 0.35, 0.38, 0.6), linewidths=0.2))
    colors = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e"]
    for i, L in enumerate(layers):
        L = np.asarray(L)
        seg = np.stack([L[edges[:, 0]], L[edges[:, 1]]], axis=1)
        lab = f"layer {i}" + (f" ({distances[i]:g} mm)" if i < len(distances) else "")
        ax.add_collection3d(Line3DCollection(seg, colors=colors[i % len(colors)], linewidths=0.7, label=lab))
    ax.legend(loc="upper left", fontsize=8)
    ax.set_title(title, fontsize=10)
    return _save(fig, path)


def picture_history(histories: list[tuple[str, list[dict]]], path: str | Path, *,
                    tolerances: dict[str, float], title: str) -> Path:
    """Max defects against iteration on a log scale, one segment per level, tolerances dashed.

    histories : ``[(label, [ {"planarity": x, "conical": y, ...}, ...]), ...]``.
    """
    fig = _figure((7.0, 4.2))
    ax = fig.add_subplot(111)
    keys = ("planarity", "conical", "circular")
    colors = {"planarity": "#1f77b4", "conical": "#d62728", "circular": "#2ca02c"}
    start, drawn = 0, False
    for n, (label, hist) in enumerate(histories):
        it = np.arange(start, start + len(hist))
        for key in keys:
            y = np.array([h.get(key, np.nan) if isinstance(h.get(key), (int, float)) else np.nan
                          for h in hist], dtype=float)
            if np.any(y > 0):
                ax.semilogy(it, np.maximum(y, FLOOR), "-o", ms=2.5, color=colors[key],
                            label=key if n == 0 else None)
                drawn = True
        if len(histories) > 1 and hist:
            ax.axvline(start - 0.5, color="0.7", lw=0.8)
            ax.text(start, 1.0, f" {label}", transform=ax.get_xaxis_transform(), va="top", fontsize=8)
        start += len(hist)
    if drawn:
        for key in keys:
            if key in tolerances and any(key in h for _, hist in histories for h in hist):
                ax.axhline(tolerances[key], color=colors[key], ls="--", lw=0.9, label=f"{key} tolerance")
        ax.legend(fontsize=8)
    else:
        ax.text(0.5, 0.5, "no optimization history", ha="center", va="center", transform=ax.transAxes)
    ax.set_xlabel("iteration")
    ax.set_ylabel("max defect (log scale)")
    ax.grid(True, which="both", alpha=0.3)
    ax.set_title(title, fontsize=10)
    return _save(fig, path)


MAX_SHEET_INCH = 48.0
MIN_FONT_PT = 3.0


def outline_label_sizes(widths_pt: np.ndarray, heights_pt: np.ndarray, ids: list[str]) -> np.ndarray:
    """(p,) font size (pt) that fits each id inside its part (``widths_pt, heights_pt (p,)``, the
    part's drawn size in points), at most 9 pt; 0 where even ``MIN_FONT_PT`` does not fit."""
    chars = np.array([max(len(i), 1) for i in ids], dtype=float)
    fs = np.minimum.reduce([0.85 * widths_pt / (0.62 * chars), 0.7 * heights_pt, np.full(len(ids), 9.0)])
    return np.where(fs >= MIN_FONT_PT, fs, 0.0)


_GLYPHS: dict[str, tuple[np.ndarray, np.ndarray, float]] = {}


def _glyph(ch: str) -> tuple[np.ndarray, np.ndarray, float]:
    """Outline vertices, path codes and advance of one character at font size 1 (cached)."""
    if ch not in _GLYPHS:
        from matplotlib.font_manager import FontProperties
        from matplotlib.textpath import TextPath, text_to_path

        prop = FontProperties(size=1.0)
        tp = TextPath((0.0, 0.0), ch, prop=prop)
        w = text_to_path.get_text_width_height_descent(ch, prop, ismath=False)[0]
        _GLYPHS[ch] = (np.asarray(tp.vertices, dtype=float), np.asarray(tp.codes), float(w))
    return _GLYPHS[ch]


def _glyph_run(text: str) -> tuple[np.ndarray, np.ndarray] | None:
    """The glyph outlines of ``text`` at size 1, centred on their bounding box (None: nothing drawn)."""
    x, parts = 0.0, []
    for ch in text:
        V, C, w = _glyph(ch)
        if len(V):
            parts.append((V + (x, 0.0), C))
        x += w
    if not parts:
        return None
    V = np.concatenate([v for v, _ in parts])
    return V - 0.5 * (V.min(axis=0) + V.max(axis=0)), np.concatenate([c for _, c in parts])


def glyph_extent(text: str) -> tuple[float, float]:
    """Width and height of the ink of ``text`` at size 1, as :func:`_id_patch` draws it."""
    run = _glyph_run(text)
    return (0.0, 0.0) if run is None else tuple(float(v) for v in np.ptp(run[0], axis=0))


def upright_or_turned(widths_pt: np.ndarray, heights_pt: np.ndarray, ids: list[str]) -> tuple[np.ndarray, np.ndarray]:
    """Font sizes ``(p,)`` as :func:`outline_label_sizes` and ``turned (p,) bool``: the id reads along
    the part's long side (turned a quarter, bottom to top) where that gives it a larger size, as on a
    tall narrow strip of a nested sheet."""
    upright = outline_label_sizes(widths_pt, heights_pt, ids)
    turned = outline_label_sizes(heights_pt, widths_pt, ids)
    turn = turned > upright
    return np.where(turn, turned, upright), turn


def _id_patch(labels: list[tuple]):
    """One patch of every id as glyph outlines in data units (mm): ``[(text, centre (2,), height mm)]``,
    or ``(text, centre, height, turned)`` (turned: read bottom to top).
    Thousands of ``ax.text`` take seconds to lay out; glyphs are made once per character and one
    compound path draws at once.  Each id's ink is centred on ``centre``: its box is ``centre`` plus or
    minus half of :func:`glyph_extent` times its size (width and height swapped when turned)."""
    from matplotlib.patches import PathPatch
    from matplotlib.path import Path as MPath

    verts, codes = [], []
    for text, centre, size, *turned in labels:
        run = _glyph_run(text)
        if run is None:
            continue
        V = run[0][:, ::-1] * (-1.0, 1.0) if turned and turned[0] else run[0]   # (x, y) -> (-y, x)
        verts.append(V * size + centre)
        codes.append(run[1])
    path = MPath(np.concatenate(verts), np.concatenate(codes)) if verts else MPath(np.zeros((0, 2)))
    return PathPatch(path, facecolor="k", edgecolor="none", lw=0)
