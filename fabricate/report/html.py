"""report.html: one self-contained page per run (pictures, tables, an interactive 3D view).

Everything the page needs lies in the run folder: the pictures, ``model.glb``,
``model_glb.js`` (the same GLB as base64, because browsers refuse ``fetch`` from
``file://``) and ``assets/three-viewer.min.js`` (three.js bundled as one classic
script, see ``fabricate/assets/build_viewer.sh``).  No network is used.
"""
from __future__ import annotations

import base64
import shutil
from html import escape
from pathlib import Path
from typing import Any

from optimize.atomic import atomic_open, atomic_path
from optimize.errors import writing

from .totals import kg, totals_lines

ASSETS = Path(__file__).resolve().parent.parent / "assets"
VIEWER_FILES = ("three-viewer.min.js", "three.LICENSE")

CSS = """
body{font:14px/1.45 system-ui,-apple-system,Segoe UI,Roboto,sans-serif;margin:0 auto;max-width:1180px;
padding:0 20px 40px;color:#1d232b}
h1{margin:18px 0 4px}h2{margin-top:30px;border-bottom:1px solid #d7dce2;padding-bottom:4px}
.banner{padding:10px 14px;border-radius:6px;margin:12px 0;font-weight:600}
.ok{background:#e3f4e6;color:#17602a}.warn{background:#fde8e6;color:#8d1d12;border:2px solid #d9392b}
table{border-collapse:collapse;margin:8px 0;font-size:13px}
td,th{border:1px solid #d7dce2;padding:3px 8px;text-align:left;vertical-align:top}
th{background:#f1f3f6}td.num{text-align:right;font-variant-numeric:tabular-nums}
.pass{color:#17602a;font-weight:600}.fail{color:#c0271b;font-weight:700}
.caution{background:#fff4d6;color:#6b4600;border:2px solid #e0a800}.warnword{color:#8a5a00;font-weight:700}.warnings{color:#8a5a00;margin:0 0 12px}
.pics{display:grid;grid-template-columns:repeat(auto-fill,minmax(480px,1fr));gap:14px}
.pics figure{margin:0}.pics img{width:100%;border:1px solid #d7dce2}
.viewer{width:100%;height:520px;border:1px solid #d7dce2;background:#f4f5f7;position:relative}
.viewer-note{position:absolute;left:10px;bottom:6px;margin:0;font-size:12px;color:#555}
code{font-size:12px}
"""

VIEWER_SCRIPT = """<script>
(function () {
  var el = document.getElementById("view");
  if (!window.FabViewer || !window.FAB_GLB) {
    el.dataset.viewer = "error";
    el.querySelector(".viewer-note").textContent =
      "the 3D view could not start: assets/three-viewer.min.js or model_glb.js is missing";
    return;
  }
  window.FabViewer.show(el, window.FAB_GLB);
})();
</script>"""


def copy_viewer(out_dir: Path, glb: bytes) -> list[str]:
    """Copy the viewer script into ``out_dir/assets`` and write ``model_glb.js``; return the file names."""
    assets = out_dir / "assets"
    assets.mkdir(exist_ok=True)
    written = []
    for name in VIEWER_FILES:
        src = ASSETS / name
        if not src.is_file():
            raise FileNotFoundError(f"{src}: the bundled 3D viewer is missing from the installation")
        with writing(assets / name, "3D viewer script", needed=src.stat().st_size), \
                atomic_path(assets / name) as tmp:
            shutil.copyfile(src, tmp)
        written.append(f"assets/{name}")
    text = "window.FAB_GLB = \"" + base64.b64encode(glb).decode("ascii") + "\";\n"
    with writing(out_dir / "model_glb.js", "3D view's model", needed=len(text)), \
            atomic_open(out_dir / "model_glb.js") as fh:
        fh.write(text)
    written.append("model_glb.js")
    return written


def _fmt(v: Any) -> str:
    if v is None:
        return ""
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, float):
        return f"{v:,.0f}" if 1000 <= abs(v) < 1e15 else f"{v:.3g}"  # a mass or length in full, never 2.92e+03
    return escape(str(v))


def _table(head: list[str], rows: list[list[Any]], raw: set[int] = frozenset()) -> str:
    th = "".join(f"<th>{escape(h)}</th>" for h in head)
    body = []
    for r in rows:
        cells = []
        for i, v in enumerate(r):
            text = v if i in raw else _fmt(v)
            cls = ' class="num"' if isinstance(v, (int, float)) and not isinstance(v, bool) else ""
            cells.append(f"<td{cls}>{text}</td>")
        body.append("<tr>" + "".join(cells) + "</tr>")
    return f"<table><tr>{th}</tr>{''.join(body)}</table>"


def _passfail(m: dict) -> str:
    p = m.get("pass")
    if p is None or m.get("role") == "reported":
        return "reported"
    if not p and not m.get("enforced"):  # information beyond its tolerance: a warning, not a failure
        return '<span class="warnword">warning</span> (information)'
    word = "pass" if p else "FAIL"
    return f'<span class="{"pass" if p else "fail"}">{word}</span>' + ("" if m.get("enforced") else " (information)")


def _measure_rows(measures: dict[str, dict]) -> list[list[Any]]:
    rows = []
    for name, m in measures.items():
        alt_txt = next((f"{_fmt(float(m[k]))} {unit}" for k, unit in (("max_mm", "mm"), ("max_deg", "deg"),
                                                              ("max_twist_mm", "mm twist"))
                        if m.get(k) is not None), "")
        elem = next((k for k in ("face", "vertex", "beam") if m.get("worst") and k in m["worst"][0]), None)
        worst = ", ".join(f"{w.get('id') or f'{elem} {w[elem]}'}: {w['value']:.2g}"  # the part id of every file
                          for w in m.get("worst", [])[:3]) if elem else ""
        rows.append([f"<b>{escape(name)}</b><br><small>{escape(m.get('what', ''))}</small>", m.get("max"),
                     m.get("unit"), alt_txt, m.get("tolerance"), _passfail(m), worst])
    return rows


def _structure_html(rep) -> str:
    from fabricate.structure.outputs import html_section

    return html_section(rep)


def status_words(report: dict[str, Any]) -> str:
    """The banner's words for a run that is not ok: ``CHECK FAILED`` when the files were written but a
    check of them failed, ``EXPORT FAILED`` when a file could not be written, else the status."""
    if report["status"] == "export_failed":
        checks = (report.get("check") or {}).get("checks") or {}
        failed = [k for k, v in checks.items() if isinstance(v, dict) and v.get("pass") is False]
        return "EXPORT FAILED" if failed and all(k.startswith("export ") for k in failed) else "CHECK FAILED"
    return report["status"].replace("_", " ").upper()


def failed_parts(check: dict[str, Any] | None) -> list[str]:
    """The part ids the failed file checks name (a clashing pair's both parts, a part whose file
    disagrees), in order, each once."""
    out: dict[str, None] = {}
    for v in ((check or {}).get("checks") or {}).values():
        if not isinstance(v, dict) or v.get("pass") is not False:
            continue
        for f in v.get("failures") or ():
            if isinstance(f, dict):
                for key in ("pair", "ids"):
                    for i in f.get(key) or ():
                        out[str(i)] = None
                for key in ("id", "part"):
                    if f.get(key):
                        out[str(f[key])] = None
    return list(out)


def highlighted_parts(check: dict[str, Any] | None, measures: dict[str, dict] | None) -> list[str]:
    """The part ids the 3D view draws in red: those the failed file checks name
    (:func:`failed_parts`) and the worst elements, by id, of every measure that fails as a requirement."""
    out = dict.fromkeys(failed_parts(check))
    for m in (measures or {}).values():
        if isinstance(m, dict) and m.get("pass") is False and m.get("enforced"):
            out.update(dict.fromkeys(str(w["id"]) for w in m.get("worst") or () if w.get("id")))
    return list(out)


def render_html(report: dict[str, Any], pictures: dict[str, str], *, viewer: bool) -> str:
    """The page as a string (``pictures``: file name -> caption)."""
    name = escape(report["name"])
    ok = report["status"] == "ok"
    from .measures import warnings

    warn = warnings(report.get("measures", {}), ((report.get("parts") or {}).get("cad_report") or {}).get("limits"))
    head = "OK: every requirement met" if not warn else f"OK with {len(warn)} warning(s): every requirement met"
    banner = (f'<div class="banner {"ok" if not warn else "caution"}">{escape(head)}</div>' if ok else
              f'<div class="banner warn">{escape(status_words(report))}: '
              f'{escape(report["message"])} (results written and marked)</div>')
    ids = failed_parts(report.get("check"))
    if ids:
        banner += (f'<p class="failed-parts">parts named by the failed checks: '
                   f'{escape(", ".join(ids[:24]) + (" ..." if len(ids) > 24 else ""))}</p>')
    if report.get("decision"):
        banner += f'<p class="decision">{escape(report["decision"])}</p>'
    if warn:
        banner += "<ul class=\"warnings\">" + "".join(f"<li>warning: {escape(w)}</li>" for w in warn) + "</ul>"
    mesh = report.get("result_mesh") or {}
    parts = report.get("parts") or {}
    inp = report.get("input") or {}
    summary = _table(["item", "value"], [
        ["input", inp.get("source")], ["levels / scheme", f"{inp.get('levels')} / {inp.get('scheme')}"],
        ["target / method", f"{inp.get('target')} / {report['config']['optimize']['method']}"],
        ["faces / vertices", f"{mesh.get('faces')} / {mesh.get('vertices')}"],
        ["bounding-box diagonal", f"{mesh.get('bbox_diagonal_mm', 0):.1f} mm"],
        ["parts", ", ".join(f"{parts[k]['count']} {k}" for k in ("panels", "beams", "nodes") if k in parts)
         or "none"],
        *[[label, line] for label, line in zip(("glass", "steel"), totals_lines(report.get("totals")))],
        ["mass", kg(parts.get('total', {}).get('mass_kg', 0)) if parts else ""],
        ["time", f"{report['timings_s'].get('before_report', 0):.2f} s (stages before the report)"]])
    measures = _table(["measure", "max", "unit", "in mm / deg", "tolerance", "result", "worst elements"],
                      _measure_rows(report.get("measures", {})), raw={0, 5})
    timings = _table(["stage", "seconds"], [[k, v] for k, v in report["timings_s"].items()])
    opt = report.get("optimization") or {}
    opt_html = (f"<p>{escape(opt.get('status', ''))}, {opt.get('nit', 0)} iterations: "
                f"{escape(opt.get('message', ''))}</p>") if opt else "<p>No optimization was run.</p>"
    levels = report.get("levels") or []
    if levels:
        opt_html += _table(["level", "faces", "status", "iterations"],
                           [[lv["level"], lv["faces"], lv["status"], lv["nit"]] for lv in levels])
    pics = "".join(f'<figure><img src="{escape(f)}" alt="{escape(c)}"><figcaption>{escape(c)}</figcaption></figure>'
                   for f, c in pictures.items())
    files = _table(["file", "bytes"], [[f'<a href="{escape(f)}">{escape(f)}</a>', v.get("bytes")]
                                      for f, v in report.get("files", {}).items()], raw={0})
    versions = _table(["package", "version"], [[k, v] for k, v in report["versions"].items()])
    notes = "".join(f"<li>{escape(n)}</li>" for n in report.get("notes", []))
    offset = "".join(f"<li>{escape(str(x))}</li>" for x in (report.get("offset") or {}).get("summary", []))
    parts_rows = [[k, v["count"], f"{v['volume_mm3'] * 1e-9:,.3f}", kg(v["mass_kg"])] for k, v in parts.items()
                  if k in ("panels", "beams", "nodes")]
    parts_html = _table(["parts", "count", "volume m3", "mass kg"], parts_rows) if parts_rows else ""
    view = ""
    if viewer:
        view = ('<h2>3D view</h2><div id="view" class="viewer" data-viewer="none">'
                '<p class="viewer-note">the 3D view needs JavaScript</p></div>'
                '<p><small>Glass panels, steel beams and nodes as built by the CAD stage; the design '
                'coloured by planarity (the scale of the picture below) and the other offset layers '
                '(red) can be switched on and off at the top right. Drag to rotate, scroll to zoom. '
                'File: <a href="model.glb">model.glb</a> (glTF, metres, y up).</small></p>'
                '<script src="assets/three-viewer.min.js"></script><script src="model_glb.js"></script>'
                + VIEWER_SCRIPT)
    return f"""<!doctype html>
<html lang="en"><head><meta charset="utf-8"><meta name="viewport" content="width=device-width">
<title>{name}: report</title><style>{CSS}</style></head>
<body data-status="{escape(report['status'])}">
<h1>{name}</h1><p><small>{escape(report['created_utc'])} &middot; config
<code>{escape(str(report.get('config_file')))}</code> &middot; exit code {report['exit_code']}</small></p>
{banner}
<h2>Summary</h2>{summary}
<h2>Measures</h2>{measures}
{view}
<h2>Pictures</h2><div class="pics">{pics or '<p>Pictures were not requested.</p>'}</div>
<h2>Optimization</h2>{opt_html}
<h2>Offset and parts</h2>{f'<ul>{offset}</ul>' if offset else ''}{parts_html}
{_structure_html(report.get("structure"))}
<h2>Timings</h2>{timings}
<h2>Files</h2>{files}
<h2>Versions</h2>{versions}
{f'<h2>Notes</h2><ul>{notes}</ul>' if notes else ''}
</body></html>
"""


def write_html(report: dict[str, Any], pictures: dict[str, str], path: str | Path, *, viewer: bool) -> Path:
    text = render_html(report, pictures, viewer=viewer)
    with writing(path, "report", needed=len(text.encode())), atomic_open(path, encoding="utf-8") as fh:
        fh.write(text)
    return Path(path)
