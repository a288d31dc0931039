"""Pictures of the structural check: the frame coloured by utilization, the deflected shape.

Drawn headless with the report's helpers (matplotlib Agg, no pyplot state), written atomically.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np


def picture_utilization(X: np.ndarray, elements: np.ndarray, utilization: np.ndarray, supports: np.ndarray,
                        path: str | Path, *, title: str) -> Path:
    """The frame, each beam coloured by its utilization (0 .. max(1, max)), supports marked.

    X : (n, 3) node coordinates mm; elements : (e, 2); utilization : (e,); supports : (k,) node indices.
    """
    from matplotlib import colormaps
    from matplotlib.colors import Normalize
    from mpl_toolkits.mplot3d.art3d import Line3DCollection

    from fabricate.report.pictures import _axes3d, _figure, _save

    fig = _figure()
    ax = _axes3d(fig, X)
    top = max(1.0, float(utilization.max(initial=0.0)))
    norm = Normalize(0.0, top)
    cmap = colormaps["RdYlGn_r"]
    seg = np.stack([X[elements[:, 0]], X[elements[:, 1]]], axis=1)
    ax.add_collection3d(Line3DCollection(seg, colors=cmap(norm(utilization)), linewidths=1.2))
    if len(supports):
        S = X[supports]
        ax.scatter(S[:, 0], S[:, 1], S[:, 2], marker="^", s=12, color="k", label=f"{len(supports)} supports")
        ax.legend(loc="upper left", fontsize=8)
    from matplotlib.cm import ScalarMappable

    sm = ScalarMappable(norm=norm, cmap=cmap)
    bar = fig.colorbar(sm, ax=ax, shrink=0.6, pad=0.08)
    bar.set_label("utilization (governing ULS combination)")
    bar.ax.axhline(1.0, color="k", linewidth=1.0)
    ax.set_title(title, fontsize=10)
    return _save(fig, path)


def deflection_scale(X: np.ndarray, U: np.ndarray, fraction: float = 0.05) -> float:
    """A round exaggeration factor that draws the largest displacement as about ``fraction`` of the frame size."""
    size = float(np.linalg.norm(X.max(axis=0) - X.min(axis=0)))
    umax = float(np.linalg.norm(U, axis=1).max(initial=0.0))
    if umax <= 0:
        return 1.0
    raw = fraction * size / umax
    p = 10.0 ** np.floor(np.log10(raw))
    return float(max(1.0, next(m * p for m in (1, 2, 5, 10) if m * p >= raw * 0.5)))


def picture_deflection(X: np.ndarray, elements: np.ndarray, U: np.ndarray, path: str | Path, *, title: str,
                       combination: str, label: str = "node displacement (mm)", unit: str = " mm") -> tuple[Path, float]:
    """The undeformed frame (grey) and the deflected one (node displacements ``U (n, 3)`` mm,
    exaggerated by the stated scale), coloured by displacement.  Returns ``(path, scale)``."""
    from matplotlib import colormaps
    from matplotlib.cm import ScalarMappable
    from matplotlib.colors import Normalize
    from mpl_toolkits.mplot3d.art3d import Line3DCollection

    from fabricate.report.pictures import _axes3d, _figure, _save

    scale = deflection_scale(X, U)
    Y = X + scale * U
    fig = _figure()
    ax = _axes3d(fig, np.concatenate([X, Y]))
    ax.add_collection3d(Line3DCollection(np.stack([X[elements[:, 0]], X[elements[:, 1]]], axis=1),
                                         colors=(0.6, 0.6, 0.6, 0.5), linewidths=0.5))
    un = np.linalg.norm(U, axis=1)
    norm = Normalize(0.0, max(float(un.max(initial=0.0)), 1e-12))
    cmap = colormaps["viridis"]
    seg = np.stack([Y[elements[:, 0]], Y[elements[:, 1]]], axis=1)
    ax.add_collection3d(Line3DCollection(seg, colors=cmap(norm(un[elements].mean(axis=1))), linewidths=1.0))
    bar = fig.colorbar(ScalarMappable(norm=norm, cmap=cmap), ax=ax, shrink=0.6, pad=0.08)
    bar.set_label(label)
    ax.set_title(f"{title}\n{combination}, displacements x {scale:g} (max {un.max(initial=0.0):.3g}{unit})",
                 fontsize=10)
    return _save(fig, path), scale
