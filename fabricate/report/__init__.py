"""Reports of a run: report.json, pictures, a GLB model and report.html.

Names load on first use (PEP 562), so importing one stage does not load the others.
"""
from optimize._lazy import lazy_exports

_EXPORTS = {
    "build_report": ".document", "jsonable": ".document", "versions": ".document",
    "write_report_json": ".document",
    "GlbMesh": ".glb", "glb_bytes": ".glb", "read_accessor": ".glb", "read_glb": ".glb",
    "write_glb": ".glb",
    "render_html": ".html", "write_html": ".html",
    "collect_measures": ".measures",
    "picture_defect": ".pictures", "picture_history": ".pictures", "picture_layers": ".pictures",
    "picture_plan": ".shop_pictures", "picture_sheets": ".shop_pictures",
    "build_scene": ".scene",
    "MARKERS": ".writer", "write_report": ".writer",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS, globals())
