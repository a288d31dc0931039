"""Where the ids go on a layout plan: scaled to their part, never on top of one another.

A shop drawing writes every mark where it can be read: a panel's id inside the
panel, as large as the panel allows (up to a cap); a beam's id beside its line,
no longer than the beam; where neither fits (a small panel, a short beam in a
dense corner) the id goes a little away, on a free spot, with a leader line to
its part; an id with no free spot nearby is left out and counted.  No text is
smaller than ``min_size``.

:func:`place_labels` is used by ``layout_plan.dxf``
(:func:`fabricate.export.cutfiles.write_layout_plan`, sizes in model mm at the
plot scale :func:`plot_scale` chooses) and by the report's ``layout_plan.png``
(:func:`fabricate.report.shop_pictures.picture_plan`, sizes from points).  Each
writer gives the box of its text at size 1 (``measure``); the boxes of the
placed labels, grown by :data:`PAD` of their size on every side, do not overlap.
Greedy, one label at a time (panels by size, then beams by length) against a
grid of the boxes already placed: linear in the number of labels.
"""
from __future__ import annotations

from collections.abc import Callable

import numpy as np

PAD = 0.15
"""Free space around every label box, in units of its size."""
SHRINK = (1.0, 0.8, 0.64, 0.5)
"""The sizes tried, as fractions of a label's preferred size (never below ``min_size``)."""
PAPER_TEXT_MM = 2.5
"""The smallest text on the plotted layout plan (mm on paper; ISO 3098's smallest usual height)."""
SCALES = (1, 2, 5, 10, 20, 25, 50, 100, 200, 250, 500, 1000, 2000, 5000)
"""Plot scale denominators a drawing uses."""
A0_MM = (1150.0, 800.0)
"""The drawing area of an A0 sheet (landscape, inside its frame and title block)."""
DXF_CHAR = (1.0, 1.0)
"""The box of one DXF TEXT character per unit of its height: width, height (the capitals and digits of
an id; 1.0 wide holds ``txt.shx`` and Arial alike)."""


def dxf_measure(text: str) -> tuple[float, float]:
    """Box (width, height) of a DXF TEXT of height 1 (:data:`DXF_CHAR` per character)."""
    return DXF_CHAR[0] * max(len(text), 1), DXF_CHAR[1]


def plot_scale(lo: np.ndarray, hi: np.ndarray, fit_mm: float) -> int:
    """The plot scale denominator of a layout plan spanning ``lo..hi`` (mm): the largest standard scale
    (:data:`SCALES`) at which the whole plan fits an A0 sheet (:data:`A0_MM`, either way round) or, when
    that is too small to read, the largest at which :data:`PAPER_TEXT_MM` text is at most half the id
    size ``fit_mm`` that fits in the median panel (a large or dense roof is plotted on several sheets,
    readable)."""
    span = np.sort(np.maximum(np.asarray(hi, float) - np.asarray(lo, float), 1.0))[::-1]
    fit = max(span[0] / A0_MM[0], span[1] / A0_MM[1])
    whole = next((s for s in SCALES if s >= fit), SCALES[-1])
    readable = max([s for s in SCALES if s <= 0.5 * fit_mm / PAPER_TEXT_MM], default=SCALES[0])
    return min(whole, readable)


def panel_fits(items: list[dict], measure: Callable[[str], tuple[float, float]]) -> np.ndarray:
    """(panels,) the largest size of each panel's id that fits in it, centred on its anchor."""
    return np.array([_fit_in_polygon(np.asarray(it["polygon"], float), np.asarray(it["anchor"], float),
                                     *measure(it["text"])) for it in items if it["kind"] == "panel"])


def _fit_in_polygon(P: np.ndarray, c: np.ndarray, w: float, h: float) -> float:
    """Largest size ``s`` at which the box ``(s w, s h)`` grown by ``PAD s``, centred at ``c``, lies in the
    convex polygon ``P (k, 2)`` (0 when ``c`` is outside)."""
    area = 0.5 * np.sum(P[:, 0] * np.roll(P[:, 1], -1) - np.roll(P[:, 0], -1) * P[:, 1])
    E = np.roll(P, -1, axis=0) - P
    m = np.stack([-E[:, 1], E[:, 0]], axis=1) * (1.0 if area > 0 else -1.0)   # inward
    L = np.linalg.norm(m, axis=1)
    keep = L > 1e-12
    m = m[keep] / L[keep, None]
    d = np.einsum("ki,ki->k", m, c - P[keep])
    need = np.abs(m[:, 0]) * (0.5 * w + PAD) + np.abs(m[:, 1]) * (0.5 * h + PAD)
    return float(max(0.0, (d / need).min())) if len(d) else 0.0


class _Grid:
    """Boxes ``(x0, y0, x1, y1)`` in a uniform grid: does a new box touch any of them."""

    def __init__(self, cell: float):
        self.cell = max(float(cell), 1e-9)
        self.cells: dict[tuple[int, int], list[int]] = {}
        self.boxes: list[tuple[float, float, float, float]] = []

    def _keys(self, b):
        c = self.cell
        for i in range(int(np.floor(b[0] / c)), int(np.floor(b[2] / c)) + 1):
            for j in range(int(np.floor(b[1] / c)), int(np.floor(b[3] / c)) + 1):
                yield i, j

    def free(self, b) -> bool:
        for key in self._keys(b):  # the few cells one box covers
            for k in self.cells.get(key, ()):
                o = self.boxes[k]
                if b[0] < o[2] and o[0] < b[2] and b[1] < o[3] and o[1] < b[3]:
                    return False
        return True

    def add(self, b) -> None:
        self.boxes.append(b)
        for key in self._keys(b):
            self.cells.setdefault(key, []).append(len(self.boxes) - 1)


def _box(c, w, h, s, pad=True):
    gx, gy = 0.5 * w * s + (PAD * s if pad else 0.0), 0.5 * h * s + (PAD * s if pad else 0.0)
    return (c[0] - gx, c[1] - gy, c[0] + gx, c[1] + gy)


def place_labels(items: list[dict], measure: Callable[[str], tuple[float, float]], min_size: float,
                 max_size: float, beam_size: float | None = None) -> list[dict]:
    """Place every label of ``items`` (in order of importance within its kind).

    items : ``{"text", "kind": "panel" | "beam", "polygon": (k, 2) convex outline (panel) or
    "segment": (2, 2) (beam), "anchor": (2,)}`` in drawing units; measure : text -> (width, height)
    of its box at size 1; min_size, max_size : text sizes (drawing units): a panel's id as large as 0.8 of
    what fits in it, within them; beam_size : a beam's id (default ``min_size``; smaller on a beam shorter
    than 1 / 0.6 of it, not below ``min_size``).
    Returns, per item in its order: ``{"text", "centre" (2,), "size", "box" (x0, y0, x1, y1) of the text
    (without the pad), "leader" ((2, 2) from the part to the box, or None), "how": "inside" (a panel's id
    in it) | "beside" (a beam's) | "leader" | "skipped"}``.
    """
    out: list[dict | None] = [None] * len(items)
    dims = [measure(it["text"]) for it in items]
    grid = _Grid(4.0 * max_size * max((d[0] for d in dims), default=1.0) / 4.0)

    def take(i, c, s, how, leader=None):
        w, h = dims[i]
        grid.add(_box(c, w, h, s))
        out[i] = {"text": items[i]["text"], "centre": np.asarray(c, float), "size": float(s),
                  "box": _box(c, w, h, s, pad=False), "leader": leader, "how": how}

    def sizes(pref):
        return sorted({max(min_size, min(max_size, pref * f)) for f in SHRINK}, reverse=True)

    panels = [i for i, it in enumerate(items) if it["kind"] == "panel"]
    beams = [i for i, it in enumerate(items) if it["kind"] != "panel"]
    fit = dict(zip(panels, panel_fits([items[i] for i in panels], measure).tolist()))
    length = {i: float(np.linalg.norm(np.subtract(*items[i]["segment"]))) for i in beams}
    beam = min_size if beam_size is None else float(beam_size)
    later = []
    for i in sorted(panels, key=lambda i: -fit[i]):  # big panels first
        c = np.asarray(items[i]["anchor"], float)
        for s in sizes(0.8 * fit[i]):
            if s <= fit[i] and grid.free(_box(c, *dims[i], s)):
                take(i, c, s, "inside")
                break
        else:
            later.append(i)
    for i in sorted(beams, key=lambda i: -length[i]):  # long beams first
        a, b = (np.asarray(p, float) for p in items[i]["segment"])
        t = (b - a) / max(length[i], 1e-12)
        n = np.array([-t[1], t[0]])
        w, h = dims[i]
        done = False
        for s in sizes(min(beam, 0.6 * length[i] / w)):
            off = 0.5 * (abs(n[0]) * w + abs(n[1]) * h) * s + 2 * PAD * s   # clear of the line
            for f in (0.5, 0.35, 0.65):
                for side in (1.0, -1.0):
                    c = a + f * (b - a) + side * off * n
                    if grid.free(_box(c, w, h, s)):
                        take(i, c, s, "beside")
                        done = True
                        break
                if done:
                    break
            if done:
                break
        if not done:
            later.append(i)
    for i in later:  # a leader from the part to the nearest free spot around it
        c0 = np.asarray(items[i]["anchor"], float)
        w, h = dims[i]
        s = min_size
        diag = float(np.hypot(w, h)) * s
        phi = np.linspace(0.0, 2 * np.pi, 16, endpoint=False)
        for r in (1.0, 1.6, 2.4, 3.5, 5.0):
            hit = None
            for u in np.stack([np.cos(phi), np.sin(phi)], axis=1):
                c = c0 + r * diag * u
                if grid.free(_box(c, w, h, s)):
                    hit = c
                    break
            if hit is not None:
                bx = _box(hit, w, h, s, pad=False)
                end = np.clip(c0, [bx[0], bx[1]], [bx[2], bx[3]])
                take(i, hit, s, "leader", np.stack([c0, end]))
                break
        else:
            out[i] = {"text": items[i]["text"], "centre": c0, "size": 0.0, "box": None, "leader": None,
                      "how": "skipped"}
    return out  # type: ignore[return-value]


def label_counts(labels: list[dict]) -> dict[str, int]:
    """How many labels went ``inside``, ``beside``, on a ``leader`` or were ``skipped``."""
    out = {"inside": 0, "beside": 0, "leader": 0, "skipped": 0}
    for lab in labels:
        out[lab["how"]] += 1
    return out


def boxes_overlap(boxes) -> list[tuple[int, int]]:
    """Pairs ``(i, j)`` of boxes ``(x0, y0, x1, y1)`` that overlap (a sweep over x; for tests and checks)."""
    B = np.asarray([b for b in boxes], dtype=float).reshape(-1, 4)
    order = np.argsort(B[:, 0])
    out, active = [], []
    for i in order.tolist():  # sweep: boxes whose x range is still open
        active = [j for j in active if B[j, 2] > B[i, 0]]
        out += [(min(i, j), max(i, j)) for j in active if B[j, 1] < B[i, 3] and B[i, 1] < B[j, 3]]
        active.append(i)
    return out
