"""Files of the offset stage: layers (OBJ), node axes and beams (OBJ + JSON), the report.

:func:`write_offset_files` writes into a folder the caller made (normally the
temporary folder of :func:`optimize.atomic.atomic_dir`, so that a failed run
leaves nothing that looks complete); every file is itself written atomically.
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from optimize.atomic import atomic_open
from optimize.errors import writing
from optimize.mesh.io import write_mesh

from .focal import focal_meshes, spherical_image, spherical_image_defect
from .structure import OffsetStructure

REPORT = "offset_report.json"


def layer_filename(text: str) -> str:
    """``layer_<distance>.obj`` with the distance as typed (``"20"`` -> ``layer_20.obj``)."""
    return f"layer_{text.strip()}.obj"


def write_json(path: Path, data) -> None:
    """Write strict JSON (no NaN) atomically."""
    with writing(path, "JSON file"), atomic_open(path, "w") as fh:
        json.dump(data, fh, indent=1, allow_nan=False)
        fh.write("\n")


def write_axes_obj(path: Path, lower: np.ndarray, upper: np.ndarray) -> None:
    """One OBJ line element per node axis, from ``lower (n, 3)`` to ``upper (n, 3)``."""
    n = len(lower)
    P = np.empty((2 * n, 3))
    P[0::2], P[1::2] = lower, upper
    with writing(path, "node axes"), atomic_open(path, "w") as fh:
        fh.write(f"# {n} node axes: line i+1 is the axis of mesh vertex i (written by conical-fab)\n")
        fh.write("".join("v %.17g %.17g %.17g\n" % tuple(p) for p in P.tolist()))
        fh.write("".join(f"l {2 * i + 1} {2 * i + 2}\n" for i in range(n)))


def _finite_or_none(A: np.ndarray) -> list:
    """Rows of ``A (k, d)`` as lists, ``None`` for a row that is not finite (JSON has no NaN/inf)."""
    ok = np.isfinite(A).all(axis=1)
    return [row if good else None for row, good in zip(A.tolist(), ok.tolist())]


def focal_data(s: OffsetStructure) -> dict:
    """Focal points per edge, the focal quads of both families and the spherical image (JSON-ready)."""
    fm = focal_meshes(s.mesh, s.axes)
    P, quads, verts = spherical_image(s.mesh, s.normals)
    sph = spherical_image_defect(s.mesh, s.normals)
    return {
        "units": "mm",
        "focal": {"edges": s.edges.tolist(), "points": _finite_or_none(fm.points),
                  "radii": _finite_or_none(fm.radii), "axis_gap": fm.gap.tolist(),
                  "family": fm.family.tolist(), "quads": fm.quads.tolist(),
                  "quad_edge": fm.quad_edge.tolist(), "quad_family": fm.quad_family.tolist(),
                  "note": "point e is where the node axes of edge e meet (null: parallel axes); "
                          "quads index points; family -1: no row/column split there"},
        "spherical_image": {"points": P.tolist(), "quads": quads.tolist(), "vertex": verts.tolist(),
                            "circular_defect_rad": [None if not np.isfinite(x) else float(x) for x in sph],
                            "note": "points are the unit face normals; quad k surrounds mesh vertex "
                                    "vertex[k]; circular (defect 0) exactly for a conical mesh"},
    }


def write_offset_files(s: OffsetStructure, folder, layer_texts=None, extra: dict | None = None) -> list[str]:
    """Write every output of the offset stage into ``folder``; return the file names.

    layer_texts : the distances as the user typed them (file names
        ``layer_<text>.obj``); default ``f"{d:g}"``.
    extra : entries added to the written report (e.g. the input path).
    Files: one ``layer_<d>.obj`` per distance (same vertex order and faces as
    the input), ``axes.obj`` / ``axes.json``, ``beams.obj`` (face ``i`` is the
    beam of edge ``i``) / ``beams.json``, ``focal.json`` (focal meshes and
    spherical image) and ``offset_report.json``.
    """
    folder = Path(folder)
    texts = list(layer_texts) if layer_texts is not None else [f"{d:g}" for d in s.distances]
    names = []
    for i, text in enumerate(texts):
        name = layer_filename(text)
        write_mesh(folder / name, s.layer_mesh(i))
        names.append(name)
    lo, hi = min(s.distances + (0.0,)), max(s.distances + (0.0,))
    write_axes_obj(folder / "axes.obj", s.mesh.V + lo * s.offset, s.mesh.V + hi * s.offset)
    write_json(folder / "axes.json", {
        "units": "mm", "extent_mm": [lo, hi], "vertices": s.mesh.V.tolist(), "axes": s.axes.tolist(),
        "cos_theta": s.cos_theta.tolist(), "axis_defect_rad": s.axis_defect.tolist(),
        "offset_vectors": s.offset.tolist(),
        "note": "layer at distance d: vertex + d * offset_vector (= axis / cos_theta)"})
    write_mesh(folder / "beams.obj", s.beam_mesh())
    write_json(folder / "beams.json", {
        "units": "mm", "span_mm": list(s.beam_span), "edges": s.edges.tolist(),
        "quads": s.beam_quads.tolist(), "normals": s.beam_normals.tolist(),
        "twist_mm": s.beam_twist_mm.tolist(), "twist_deg": s.beam_twist_deg.tolist(),
        "note": "quad i = [a@d0, b@d0, b@d1, a@d1] for edge i = (a, b); beams.obj face i is quad i"})
    write_json(folder / "focal.json", focal_data(s))
    names += ["axes.obj", "axes.json", "beams.obj", "beams.json", "focal.json"]
    report = {**s.report, **(extra or {})}
    report["files"] = {"layers": dict(zip((f"{d:g}" for d in s.distances), names[: len(texts)])),
                       "axes": ["axes.obj", "axes.json"], "beams": ["beams.obj", "beams.json"],
                       "analysis": ["focal.json"]}
    write_json(folder / REPORT, report)
    names.append(REPORT)
    return names
