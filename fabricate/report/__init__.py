"""Reports of a run: report.json, pictures, a GLB model and report.html."""
from .document import build_report, jsonable, versions, write_report_json
from .glb import GlbMesh, glb_bytes, read_accessor, read_glb, write_glb
from .html import render_html, write_html
from .measures import collect_measures
from .pictures import picture_defect, picture_history, picture_layers, picture_outlines
from .scene import build_scene
from .writer import MARKERS, write_report

__all__ = ["GlbMesh", "MARKERS", "build_report", "build_scene", "collect_measures", "glb_bytes", "jsonable",
           "picture_defect", "picture_history", "picture_layers", "picture_outlines", "read_accessor",
           "read_glb", "render_html", "versions", "write_glb", "write_html", "write_report",
           "write_report_json"]
