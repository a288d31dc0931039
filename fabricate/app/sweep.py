"""Exploration at scale (#37 item 4): a batch sweep as a design-space explorer reads it, and its Pareto front.

``fabricate batch configs/dome.yaml --set optimize.rationalize=null,20,50,100`` runs one job per
value; besides ``batch_summary.csv`` it writes, beside that file:

- ``sweep.csv``: one row per job in the columns Design Explorer (Thornton Tomasetti) and tools like
  it read: ``in:<key>`` per swept key (``in:config`` when the batch has several configs), ``out:`` the
  figures of the job's report.json (:data:`OUTPUTS`: distinct glass shapes, node and beam types, how
  far the design moved in mm and in % of its bounding-box diagonal, the roughness ratio, the status,
  whether it is on the Pareto front) and ``img:classes``, the job's ``classes.png`` relative to the
  CSV (its ``planarity.png`` when it has no glass, empty without pictures);
- ``pareto.png``: distinct glass shapes against the distance moved (mm), one point per job, the
  Pareto front (no other job has as few shapes for as little movement) joined and labelled with
  its swept values; jobs that did not end ``ok`` drawn apart and never on the front;
- ``pareto.csv``: the front's jobs, fewest shapes last.

The figures are read by the worker that ran the job (:func:`job_facts`, in :func:`fabricate.app.batch.run_job`),
so that a Dask cluster's results reach the table even where the client cannot read the run folders.
"""
from __future__ import annotations

import csv
import io
import json
import math
import os
from pathlib import Path
from typing import Any

import numpy as np

from optimize.atomic import atomic_open, atomic_path
from optimize.errors import writing

IN, OUT, IMG = "in:", "out:", "img:"
OUTPUTS = (("glass shapes", "glass_shapes"), ("node types", "node_types"), ("beam types", "beam_types"),
           ("moved mm", "moved_mm"), ("moved %", "moved_pct"), ("roughness ratio", "roughness"))
"""``out:`` columns and their :func:`job_facts` keys (then ``out:status`` and ``out:pareto``)."""
PICTURES = ("classes.png", "planarity.png")
"""The ``img:`` column's picture of a job: the first of these its run wrote."""
HEADS = {"glass shapes": "glass\nshapes", "node types": "node\ntypes", "beam types": "beam\ntypes",
         "moved mm": "moved\nmm", "moved %": "moved\n%", "roughness ratio": "rough-\nness"}
"""The terminal table's headers, in two lines."""
FILES = {"table": "sweep.csv", "front": "pareto.csv", "plot": "pareto.png"}


def job_facts(out_dir: str | Path | None) -> dict[str, Any]:
    """The sweep's figures of a finished run folder (its report.json); ``{}`` when there is none.

    ``glass_shapes``, ``panels`` (totals: mirror images as one shape), ``node_types``, ``beam_types``,
    ``moved_mm`` and ``moved_pct`` (measures.closeness: the largest distance to the design, in mm and
    in % of the bounding-box diagonal), ``roughness`` (measures.roughness: the result's over the
    input's), ``picture`` (the file of :data:`PICTURES` the run wrote, relative to its folder)."""
    if not out_dir:
        return {}
    folder = Path(out_dir)
    try:
        report = json.loads((folder / "report.json").read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}
    totals = report.get("totals") or {}
    measures = report.get("measures") or {}
    close, rough = measures.get("closeness") or {}, measures.get("roughness") or {}
    pct = close.get("max")
    return {"glass_shapes": totals.get("glass_shapes"), "panels": totals.get("panels"),
            "node_types": totals.get("node_types"), "beam_types": totals.get("beam_types"),
            "moved_mm": close.get("max_mm"), "moved_pct": None if pct is None else 100.0 * pct,
            "roughness": rough.get("max"),
            "picture": next((p for p in PICTURES if (folder / p).is_file()), None)}


def pareto_front(x, y) -> np.ndarray:
    """(n,) bool: the points no other point dominates when both ``x`` and ``y`` are minimized (another
    at most as large in both and smaller in one); equal points are all on the front; NaN never."""
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    front = np.zeros(len(x), dtype=bool)
    best, last = math.inf, None
    for i in np.lexsort((y, x)).tolist():  # by x, then y
        if not (np.isfinite(x[i]) and np.isfinite(y[i])):
            continue
        if y[i] < best:
            front[i], best, last = True, y[i], i
        elif last is not None and y[i] == y[last] and x[i] == x[last]:
            front[i] = True
    return front


def _text(value: Any) -> str:
    """A swept value as it would be typed in --set (None: ``null``)."""
    if value is None:
        return "null"
    if isinstance(value, bool):
        return str(value).lower()
    if isinstance(value, float):
        return f"{value:g}"
    return str(value).replace(" ", "")


def inputs(jobs) -> list[str]:
    """The swept keys of ``jobs`` (their values differ), in ``--set`` order; ``config`` first when the
    batch has several configs; every set key (or ``config``) when nothing differs."""
    keys = list(dict.fromkeys(k for j in jobs for k in j.overrides))
    swept = [k for k in keys if len({_text(j.overrides.get(k)) for j in jobs}) > 1]
    several = len({j.config_file for j in jobs}) > 1
    return (["config"] if several or not (swept or keys) else []) + (swept or keys)


def sweep_rows(jobs, summaries, folder: str | Path) -> list[dict[str, str]]:
    """One row per job of ``sweep.csv`` (columns :func:`columns`), ``img:`` relative to ``folder``."""
    keys = inputs(jobs)

    def figure(s, key):  # as the CSV writes it (6 digits): jobs that differ by rounding noise are equal
        v = s.facts.get(key) if s.status == "ok" else None
        return np.nan if v is None else float(f"{v:.6g}")

    front = pareto_front([figure(s, "moved_mm") for s in summaries], [figure(s, "glass_shapes") for s in summaries])
    rows = []
    for job, s, on in zip(jobs, summaries, front.tolist()):
        row = {IN + k: (Path(job.config_file).stem if k == "config" else _text(job.overrides.get(k))) for k in keys}
        for col, key in OUTPUTS:
            v = s.facts.get(key)
            row[OUT + col] = "" if v is None else f"{v:.6g}" if isinstance(v, float) else str(v)
        row[OUT + "status"] = s.status
        row[OUT + "pareto"] = "1" if on else "0"
        pic = s.facts.get("picture")
        row[IMG + "classes"] = (Path(os.path.relpath(Path(s.out_dir) / pic, folder)).as_posix()
                                if pic and s.out_dir else "")
        rows.append(row)
    return rows


def columns(rows: list[dict[str, str]]) -> list[str]:
    return list(rows[0]) if rows else [IN + "config"] + [OUT + c for c, _ in OUTPUTS] + [OUT + "status",
                                                                                         OUT + "pareto", IMG + "classes"]


def _write_csv(rows: list[dict[str, str]], fields: list[str], path: Path, what: str) -> Path:
    buf = io.StringIO()
    writer = csv.DictWriter(buf, fieldnames=fields, extrasaction="ignore")
    writer.writeheader()
    writer.writerows(rows)
    text = buf.getvalue()
    with writing(path, what, needed=len(text.encode())), atomic_open(path, newline="") as fh:
        fh.write(text)
    return path


def _label(row: dict[str, str]) -> str:
    return ", ".join(f"{k[len(IN):].split('.')[-1]}={v}" for k, v in row.items() if k.startswith(IN))


def picture_pareto(rows: list[dict[str, str]], path: str | Path, *, title: str) -> Path:
    """``pareto.png``: distinct glass shapes against the distance moved (mm), one point per job with both
    figures; the front (``out:pareto``) joined and labelled with the swept values; jobs not ``ok`` as
    grey crosses."""
    from fabricate.report.pictures import DPI, _figure

    def num(r, col):
        return float(r[OUT + col]) if r.get(OUT + col) not in (None, "") else math.nan

    x = np.array([num(r, "moved mm") for r in rows])
    y = np.array([num(r, "glass shapes") for r in rows])
    ok = np.array([r[OUT + "status"] == "ok" for r in rows], dtype=bool)
    on = np.array([r[OUT + "pareto"] == "1" for r in rows], dtype=bool)
    drawn = np.isfinite(x) & np.isfinite(y)
    fig = _figure((7.0, 5.0))
    ax = fig.add_subplot(111)
    sel = drawn & ok & ~on
    if sel.any():
        ax.plot(x[sel], y[sel], "o", color="#1f77b4", ms=5, label="a job")
    sel = drawn & ~ok
    if sel.any():
        ax.plot(x[sel], y[sel], "x", color="0.55", ms=6, label="a job that did not end ok (not on the front)")
    idx = np.flatnonzero(on & drawn)
    if len(idx):
        idx = idx[np.lexsort((y[idx], x[idx]))]
        ax.plot(x[idx], y[idx], "-o", color="#d62728", ms=6, lw=1.5, label="Pareto front")
    groups: dict[tuple[float, float], list[int]] = {}
    for i in np.flatnonzero(drawn).tolist():  # jobs at the same point share one label
        groups.setdefault((float(x[i]), float(y[i])), []).append(i)
    for (px, py), members in groups.items():  # the front's labels black above, the others' grey below
        front = any(on[i] for i in members)
        text = _label(rows[members[0]]) + (f" (and {len(members) - 1} more)" if len(members) > 1 else "")
        ax.annotate(text, (px, py), textcoords="offset points", xytext=(6, 5 if front else -11), fontsize=7,
                    color="k" if front else "0.45")
    if not drawn.any():
        ax.text(0.5, 0.5, "no job with both figures", ha="center", va="center", transform=ax.transAxes)
    else:
        ax.legend(fontsize=8, loc="best")
    from matplotlib.ticker import MaxNLocator

    ax.yaxis.set_major_locator(MaxNLocator(integer=True))
    ax.margins(0.12)
    ax.set_xlabel("distance moved from the design (mm, largest vertex)")
    ax.set_ylabel("distinct glass shapes (within the size tolerance)")
    ax.grid(True, alpha=0.3)
    ax.set_title(title, fontsize=10)
    path = Path(path)
    with writing(path, "picture"), atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", dpi=DPI, bbox_inches="tight")
    return path


def write_sweep(jobs, summaries, folder: str | Path) -> tuple[list[dict[str, str]], dict[str, Path]]:
    """``sweep.csv``, ``pareto.csv`` and ``pareto.png`` of a finished batch into ``folder``; the rows and
    the files."""
    folder = Path(folder)
    rows = sweep_rows(jobs, summaries, folder)
    fields = columns(rows)
    files = {"table": _write_csv(rows, fields, folder / FILES["table"], "sweep table")}
    front = [dict(r, **{"name": s.name}) for r, s in zip(rows, summaries) if r[OUT + "pareto"] == "1"]
    front.sort(key=lambda r: (float(r[OUT + "moved mm"]), float(r[OUT + "glass shapes"])))
    files["front"] = _write_csv(front, ["name"] + fields, folder / FILES["front"], "Pareto front")
    keys = ", ".join(k[len(IN):] for k in fields if k.startswith(IN))
    files["plot"] = picture_pareto(rows, folder / FILES["plot"],
                                   title=f"{len(rows)} jobs ({keys}): distinct glass shapes against distance moved")
    return rows, files


def print_sweep(rows: list[dict[str, str]], console=None) -> None:
    """The sweep table on the terminal (fits 80 columns with two swept keys): the swept values and the
    figures, ``*`` after the status of a job on the front."""
    from rich import box
    from rich.console import Console
    from rich.table import Table

    if not rows:
        return
    table = Table(title=f"sweep: {sum(r[OUT + 'pareto'] == '1' for r in rows)} of {len(rows)} jobs on the "
                        "Pareto front (*: no other job has as few glass shapes for as little movement)",
                  box=box.SIMPLE_HEAD, padding=(0, 1), pad_edge=False, collapse_padding=True)
    keys = [k for k in rows[0] if k.startswith(IN)]
    outs = [OUT + c for c, _ in OUTPUTS]
    for k in keys:
        table.add_column(k[len(IN):].split(".")[-1], justify="right", overflow="fold")
    for k in outs:
        table.add_column(HEADS.get(k[len(OUT):], k[len(OUT):]), justify="right", no_wrap=True)
    table.add_column("status", justify="left", min_width=6)
    for r in rows:
        status = r[OUT + "status"].replace("tolerance_not_reached", "tolerance not met").replace("_", " ")
        table.add_row(*[r[k] for k in keys], *[_short(k, r[k]) for k in outs],
                      status + (" *" if r[OUT + "pareto"] == "1" else ""))
    (console or Console()).print(table)


def _short(col: str, text: str) -> str:
    if not text or col.endswith(("types", "shapes")):
        return text
    v = float(text)
    return f"{v:,.1f}" if col.endswith("mm") else f"{v:.2f}" if col.endswith("%") else f"{v:.3g}"
