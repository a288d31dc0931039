"""A user's own roof, end to end (#30): real meshes nobody here made, given with a config of just
``input`` and ``units``, run through ``fabricate run`` as a user would.

Prints per roof: the route the run chose (its first words), the exit code, how far the design
moved (mm and % of the bounding-box diagonal), the roughness ratio to the input, the worst beam
twist (mm), the worst beam planarity, folded and degenerate faces, and the seconds the run took.
The shipped roofs are ``configs/meshes/compas_quadmesh.obj`` and ``compas_tubemesh.obj`` (COMPAS,
MIT) and the tunnel; more mesh files (any unit: ``PATH:m``) may be given on the command line, e.g.
libigl's ``halftunnel.off``.

    python benchmarks/bench_own_roofs.py [--full] [MESH[:UNIT] ...]

``--full`` writes every file of a run (STEP, IFC, cut files ...) and runs the full check; by
default the CAD files are built but only the mesh, the layers and the report are written.
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
ROOFS = [(REPO / "configs" / "meshes" / "compas_quadmesh.obj", "m"),
         (REPO / "configs" / "meshes" / "compas_tubemesh.obj", "m"),
         (REPO / "configs" / "meshes" / "tunnel.off", "m")]
LIGHT = {"step": False, "stl": False, "3mf": False, "dxf": False, "svg": False, "ifc": False, "3dm": False,
         "nc1": False, "gltf": False, "pictures": False, "html": False, "glass_order": False}


def run_roof(path: Path, unit: str, folder: Path, full: bool) -> dict:
    """One roof through ``fabricate run`` in a child process; its figures from report.json."""
    name = path.stem.replace(".", "_")
    cfg = folder / f"{name}.yaml"
    text = f"name: {name}\ninput: {{mesh: {json.dumps(str(path))}}}\nunits: {unit}\n"
    if not full:
        text += "outputs: " + json.dumps(LIGHT) + "\n"
    cfg.write_text(text)
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "fabricate", "run", str(cfg), "--out", str(folder / "out"), "-q",
                           "--force"], capture_output=True, text=True, cwd=REPO)
    seconds = time.perf_counter() - t0
    out = {"roof": path.name, "unit": unit, "exit": proc.returncode, "seconds": seconds}
    report = folder / "out" / name / "report.json"
    if not report.is_file():
        out["error"] = (proc.stderr.strip().splitlines() or ["no report"])[-1][:160]
        return out
    r = json.loads(report.read_text())
    m = r.get("measures", {})
    close, rough = m.get("closeness", {}), m.get("roughness", {})
    twist = m.get("beam_twist", {})
    out.update(route=(r.get("decision") or "").split(":")[1].split(",")[0].strip() if r.get("decision") else "-",
               moved_mm=close.get("max_mm"), moved_pct=100 * close["max"] if close.get("max") is not None else None,
               roughness=rough.get("max"), twist_mm=twist.get("max"),
               folded=m.get("folded", {}).get("max"), degenerate=m.get("degenerate", {}).get("max"),
               parts=r.get("parts") is not None, message=r.get("message", "")[:120])
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("meshes", nargs="*", help="more mesh files, MESH or MESH:UNIT (default unit mm)")
    ap.add_argument("--full", action="store_true", help="write every file and run the full check")
    args = ap.parse_args(argv)
    roofs = list(ROOFS)
    for item in args.meshes:
        path, _, unit = item.partition(":")
        roofs.append((Path(path).resolve(), unit or "mm"))
    print(f"{'roof':24} {'exit':>4} {'route':38} {'moved mm':>9} {'%':>6} {'rough':>6} {'twist mm':>9} "
          f"{'fold':>4} {'degen':>5} {'parts':>5} {'s':>6}")
    with tempfile.TemporaryDirectory() as tmp:
        for path, unit in roofs:
            r = run_roof(path, unit, Path(tmp), args.full)
            if "error" in r:
                print(f"{r['roof']:24} {r['exit']:>4} {r['error']}")
                continue

            def f(x, fmt):
                return "-" if x is None else format(x, fmt)
            print(f"{r['roof']:24} {r['exit']:>4} {r['route'][:38]:38} {f(r['moved_mm'], '9.1f')} "
                  f"{f(r['moved_pct'], '6.2f')} {f(r['roughness'], '6.2f')} {f(r['twist_mm'], '9.3g')} "
                  f"{f(r['folded'], '4.0f')} {f(r['degenerate'], '5.0f')} {str(r['parts']):>5} {r['seconds']:6.1f}")
            if r["exit"] != 0:
                print(f"{'':24}      {r['message']}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
