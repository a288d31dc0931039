"""For the checking engineer: reactions and member end forces as CSV, and the analysis model as a
standalone OpenSees script (#35 item 8).

- ``reactions.csv``: one row per supported node and load (every basic load case, then every
  combination): the node's id, its OpenSees tag and position (mm), the reaction Fx Fy Fz (kN) and
  Mx My Mz (kNm) in global axes (a sprung node: the force in its springs);
- ``member_forces.csv``: one row per beam, end (i, j) and load: N Vy Vz (kN), T My Mz (kNm) in the
  beam's local axes, the forces the nodes put on the member end (OpenSees ``localForce``);
- ``structure_model.py``: the model in openseespy calls (units N, mm, MPa, rad), written by the same
  :func:`~fabricate.structure.engine.build_model`, :func:`~fabricate.structure.engine.analysis` and
  :func:`~fabricate.structure.engine.add_loads` that build the solved model: they are called here on a
  :class:`Recorder`, which writes each call as a line of Python instead of making it.  Run by itself it
  analyses every case (and the second-order combinations as the check did) and writes
  ``structure_model_reactions.csv`` and ``structure_model_member_forces.csv`` next to itself, in the
  columns of the two files above.

Combinations are the superposition of the cases with their factors, except those the check solved
second order (``analysis``: ``P-Delta`` on the imperfect geometry, or the first-order forces
``amplified``); the ``governs`` column marks the check's governing ULS and SLS combination, and per
node (the largest reaction force) or beam (its utilization) the ULS combination that governs it.
"""
from __future__ import annotations

import csv
import numbers
import time
from pathlib import Path

import numpy as np

from .engine import SECOND_ORDER_STEPS, add_loads, analysis, build_model, second_order_model
from .loads import combine

REACTIONS = "reactions.csv"
MEMBER_FORCES = "member_forces.csv"
SCRIPT = "structure_model.py"

REACTION_COLUMNS = ("load", "kind", "analysis", "governs", "node", "opensees_node", "x_mm", "y_mm", "z_mm",
                    "Fx_kN", "Fy_kN", "Fz_kN", "Mx_kNm", "My_kNm", "Mz_kNm")
MEMBER_COLUMNS = ("load", "kind", "analysis", "governs", "beam", "opensees_element", "end", "node",
                  "N_kN", "Vy_kN", "Vz_kN", "T_kNm", "My_kNm", "Mz_kNm")
REACTION_NOTE = ("# reactions of the supports in global axes (the forces the supports put on the structure): "
                 "F kN, M kNm, coordinates mm; kind 'case' (characteristic) or the combination's 'uls' / 'sls'")
MEMBER_NOTE = ("# member end forces in the beam's local axes (OpenSees localForce: the forces the nodes put on the "
               "member end; internal forces at end i are minus these, at end j these, so tension is N_j > 0): x from "
               "node i to node j, y in the beam plane (the section depth, strong-axis bending Mz), z = x cross y "
               "(the beam-plane normal, weak-axis bending My); N V kN, T M kNm")
FIRST_ORDER = "first order"
DIGITS = ".10g"


class Recorder:
    """Stands in for ``openseespy.opensees``: every call ``ops.name(*args)`` becomes the line
    ``ops.name(args)`` of Python (numbers written exactly: ``repr`` of the float)."""

    def __init__(self) -> None:
        self.lines: list[str] = []

    def __getattr__(self, name: str):
        if name.startswith("_"):
            raise AttributeError(name)

        def call(*args):
            self.lines.append(f"ops.{name}({', '.join(_literal(a) for a in args)})")
        return call

    def take(self, indent: str = "    ") -> str:
        """The lines recorded since the last call, indented (a function body)."""
        out = "\n".join(indent + ln for ln in self.lines) or indent + "pass"
        self.lines = []
        return out


def _literal(a) -> str:
    if isinstance(a, str):
        return repr(a)
    if isinstance(a, (bool, np.bool_, numbers.Integral)):
        return str(int(a))
    if isinstance(a, numbers.Real):
        return repr(float(a))
    raise TypeError(f"the model script cannot write the argument {a!r} ({type(a).__name__})")


# -- the loads: cases and combinations with what the check did -------------------------------------------------
def loads(check) -> list[tuple[str, str, str, dict]]:
    """``[(name, kind, analysis, {solution entry: factor})]``: every basic case (kind ``case``), then every
    combination of the check (``uls`` | ``sls``) with the entries of ``check.solution`` it is made of: its
    cases and factors (``first order``) or its own second-order entry (``P-Delta`` | ``amplified ...``)."""
    from .check import SECOND

    done = check.stability.second_order if check.stability is not None else {}
    out = [(name, "case", FIRST_ORDER, {name: 1.0}) for name in check.cases]
    for name, kind, factors in check.options.combination_list():
        if name in done:
            out.append((name, kind, done[name], {name + SECOND: 1.0}))
        else:
            out.append((name, kind, FIRST_ORDER, dict(factors)))
    return out


def _mix(store: dict, factors: dict) -> np.ndarray:
    return sum(f * store[k] for k, f in factors.items())


def _ids(ids, n: int, prefix: str) -> list[str]:
    return list(ids) if len(ids) == n else [f"{prefix}{i + 1}" for i in range(n)]


def _num(v: float) -> str:
    return format(float(v), DIGITS)


def reaction_rows(check) -> list[tuple]:
    """The rows of ``reactions.csv`` (:data:`REACTION_COLUMNS`), loads in :func:`loads` order."""
    fr, r = check.frame, check.results
    sup = np.nonzero(fr.supported())[0]
    names = _ids(fr.node_ids, fr.n_nodes, "N")
    gov_uls = r.uls[int(r.governing[int(np.argmax(r.utilization))])] if r.uls and fr.n_elements else ""
    rows_of = [(name, kind, how, _mix(check.solution.reactions, f)[sup]) for name, kind, how, f in loads(check)]
    uls = [k for k, (_, kind, _, _) in enumerate(rows_of) if kind == "uls"]
    node_max = np.full(len(sup), -1)
    if uls:  # per node: the ULS combination with the largest reaction force
        size = np.stack([np.linalg.norm(rows_of[k][3][:, :3], axis=1) for k in uls])
        node_max = np.asarray(uls)[np.argmax(size, axis=0)]
    out = []
    for k, (name, kind, how, R) in enumerate(rows_of):
        frame_tags = [t for t, hit in (("frame ULS", kind == "uls" and name == gov_uls),
                                       ("frame SLS", kind == "sls" and name == r.governing_sls)) if hit]
        for j, i in enumerate(sup.tolist()):
            tags = frame_tags + (["node max F"] if node_max[j] == k else [])
            out.append((name, kind, how, "; ".join(tags), names[i], i + 1, *(_num(v) for v in fr.X[i]),
                        *(_num(v * 1e-3) for v in R[j, :3]), *(_num(v * 1e-6) for v in R[j, 3:])))
    return out


def member_rows(check) -> list[tuple]:
    """The rows of ``member_forces.csv`` (:data:`MEMBER_COLUMNS`), loads in :func:`loads` order."""
    fr, r = check.frame, check.results
    beams = _ids(fr.ids, fr.n_elements, "B")
    nodes = _ids(fr.node_ids, fr.n_nodes, "N")
    gov_uls = r.uls[int(r.governing[int(np.argmax(r.utilization))])] if r.uls and fr.n_elements else ""
    beam_gov = np.array(r.uls, dtype=object)[r.governing] if r.uls else np.array([""] * fr.n_elements, dtype=object)
    out = []
    for name, kind, how, f in loads(check):
        F = _mix(check.solution.end_forces, f)
        frame_tags = [t for t, hit in (("frame ULS", kind == "uls" and name == gov_uls),
                                       ("frame SLS", kind == "sls" and name == r.governing_sls)) if hit]
        for k, (a, b) in enumerate(fr.elements.tolist()):
            tags = "; ".join(frame_tags + (["beam utilization"] if kind == "uls" and beam_gov[k] == name else []))
            for end, node, cols in (("i", a, F[k, :6]), ("j", b, F[k, 6:])):
                out.append((name, kind, how, tags, beams[k], k + 1, end, nodes[node],
                            *(_num(v * 1e-3) for v in cols[:3]), *(_num(v * 1e-6) for v in cols[3:])))
    return out


def _write_csv(path: Path, note: str, columns, rows, what: str) -> dict:
    from optimize.atomic import atomic_open
    from optimize.errors import write_error

    t0 = time.perf_counter()
    try:
        with atomic_open(path, "w", encoding="utf-8", newline="") as fh:
            fh.write(note + "\n")
            w = csv.writer(fh)
            w.writerow(columns)
            w.writerows(rows)
    except OSError as exc:
        raise write_error(path, what, exc) from exc
    return {"file": path.name, "bytes": path.stat().st_size, "rows": len(rows), "seconds": time.perf_counter() - t0}


# -- the model script ---------------------------------------------------------------------------------------------
def model_script(check, name: str = "") -> str:
    """The text of ``structure_model.py``: the model of ``check`` (a StructureCheck) in openseespy calls,
    every load case and second-order combination, and the code that solves them and writes the CSVs."""
    fr = check.frame
    rec = Recorder()
    model = build_model(rec, fr)
    build = rec.take()
    analysis(rec, fr)
    setup = rec.take()
    case_funcs, fixed_end = [], {}
    for k, (cname, case) in enumerate(check.cases.items()):
        rec.timeSeries("Linear", 1)
        add_loads(rec, 1, 1, case, model.axes)
        case_funcs.append(f"def load_case_{k + 1}():\n    \"\"\"{cname}\"\"\"\n{rec.take()}\n")
        if case.fixed_end is not None and np.abs(case.fixed_end).max(initial=0.0) > 0:
            fixed_end[cname] = {k + 1: [float(v) for v in row] for k, row in enumerate(case.fixed_end.tolist())
                                if any(row)}
    factors_of = {n: dict(f) for n, _, f in check.options.combination_list()}
    combos, second = [], []
    for cname, kind, how, _ in loads(check):
        if kind == "case":
            continue
        if how == "P-Delta":
            X = check.stability.geometry[cname]
            _, wl = second_order_model(rec, fr, combine(check.cases, factors_of[cname], cname), X)
            second.append(f"def second_order_{len(second) + 1}():\n    \"\"\"{cname}: P-Delta on the imperfect "
                          f"geometry\"\"\"\n{rec.take()}\n")
            combos.append((cname, kind, how, factors_of[cname], f"second_order_{len(second)}", 1.0))
        elif how.startswith("amplified"):
            a = check.stability.alphas[cname]
            combos.append((cname, kind, how, factors_of[cname], None, 1.0 / (1.0 - 1.0 / a)))
        else:
            combos.append((cname, kind, how, factors_of[cname], None, 1.0))
    names = _ids(fr.node_ids, fr.n_nodes, "N")
    beams = _ids(fr.ids, fr.n_elements, "B")
    supports = [(names[i], i + 1, [model.ground[i]] if i in model.ground else [])
                for i in np.nonzero(fr.supported())[0].tolist()]
    beam_rows = [(beams[k], k + 1, names[a], names[b]) for k, (a, b) in enumerate(fr.elements.tolist())]
    X = [[float(v) for v in x] for x in fr.X.tolist()]
    coords = {i + 1: X[i] for i in np.nonzero(fr.supported())[0].tolist()}
    combo_lines = ",\n".join(
        f"    ({n!r}, {k!r}, {h!r}, {dict((c, float(v)) for c, v in f.items())!r}, {fn or 'None'}, {repr(float(m))})"
        for n, k, h, f, fn, m in combos)
    return _TEMPLATE.format(
        name=name or "structure", n=fr.n_nodes, e=fr.n_elements, joints=_joints(fr), E=repr(float(fr.E)),
        G=repr(float(fr.G)), steps=SECOND_ORDER_STEPS, reaction_columns=repr(REACTION_COLUMNS),
        member_columns=repr(MEMBER_COLUMNS), reaction_note=repr(REACTION_NOTE), member_note=repr(MEMBER_NOTE),
        supports=repr(supports), coords=repr(coords), beams=repr(beam_rows), cases=repr(list(check.cases)),
        fixed_end=repr(fixed_end), digits=repr(DIGITS), build=build, setup=setup,
        case_funcs="\n\n".join(case_funcs), second="\n\n".join(second) or "# (no combination solved second order)\n",
        combos=combo_lines, first=repr(FIRST_ORDER))


def _joints(fr) -> str:
    return "pinned" if fr.pinned else f"semi-rigid ({fr.joint_stiffness:g} N mm/rad)" if fr.semi_rigid else "rigid"


_TEMPLATE = '''#!/usr/bin/env python3
"""{name}: the structural analysis model of conical-fab's structure check, as an OpenSees script.

Units: N, mm, MPa (N/mm2), rad.  {n} nodes, {e} beams (elasticBeamColumn, E {E}, G {G}; the elements'
Iy argument is the section's weak-axis, Iz its strong-axis moment of inertia), {joints} joints.
Node tags 1..{n} are the structure's nodes (SUPPORTS and BEAMS name them with the run's ids); higher
tags are the ground nodes of support springs and the end nodes of semi-rigid joints.  Element tags
1..{e} are the beams; higher tags the zeroLength springs.

Run it with the Python that has openseespy (pip install openseespy):
    python structure_model.py [output folder]
Every load case is solved on its own (linear elastic), the combinations are their superposition
with the factors below, except those the check solved second order (P-Delta on the imperfect geometry
written below, Newton in {steps} increments) or amplified by 1 / (1 - 1 / alpha_cr).  It writes
structure_model_reactions.csv and structure_model_member_forces.csv (into the output folder, by default
next to this file) in the columns of the run's reactions.csv and member_forces.csv.
"""
import csv
import os
import sys


def _import_opensees():
    """openseespy; on Linux its wheel's own BLAS is loaded first (the wheel does not find it everywhere)."""
    import ctypes
    import importlib.util
    spec = importlib.util.find_spec("openseespylinux")
    if spec is not None and spec.origin:
        blas = os.path.join(os.path.dirname(spec.origin), "lib", "libblas.so.3")
        if os.path.exists(blas):
            ctypes.CDLL(blas, mode=ctypes.RTLD_LOCAL)
    import openseespy.opensees as ops
    return ops


ops = _import_opensees()

REACTION_COLUMNS = {reaction_columns}
MEMBER_COLUMNS = {member_columns}
REACTION_NOTE = {reaction_note}
MEMBER_NOTE = {member_note}
SUPPORTS = {supports}
"""(node id, node tag, [tags of the fixed ground nodes of its springs])"""
COORDINATES = {coords}
BEAMS = {beams}
"""(beam id, element tag, node id at end i, node id at end j)"""
CASES = {cases}
FIXED_END = {fixed_end}
"""{{case: {{element tag: 12 local end forces}}}}: members held against an imposed strain (temperature): their
end forces, added to the solved ones (the equivalent nodal loads are in the case's pattern)."""


def build_model():
{build}


def analysis():
{setup}


{case_funcs}

{second}

COMBINATIONS = [
{combos}
]
"""(name, uls | sls, analysis, {{case: factor}}, second-order model or None, amplification)"""


def solve(name, parts, steps=1):
    """Build, load and analyse (``parts`` called in order); returns (reactions {{tag: 6}}, end forces
    {{tag: 12}}) in N and N mm."""
    ops.wipe()
    for part in parts:
        part()
    for _ in range(steps):
        if ops.analyze(1) != 0:
            raise SystemExit(f"OpenSees did not converge under {{name}}")
    ops.reactions()
    R = {{}}
    for _, tag, ground in SUPPORTS:
        R[tag] = [sum(v) for v in zip(ops.nodeReaction(tag), *(ops.nodeReaction(g) for g in ground))]
    F = {{tag: list(ops.eleResponse(tag, "localForce")) for _, tag, _, _ in BEAMS}}
    ops.wipe()
    return R, F


def mix(results, factors, scale=1.0):
    R = {{t: [scale * sum(f * results[c][0][t][d] for c, f in factors.items()) for d in range(6)]
         for _, t, _ in SUPPORTS}}
    F = {{t: [scale * sum(f * results[c][1][t][d] for c, f in factors.items()) for d in range(12)]
         for _, t, _, _ in BEAMS}}
    return R, F


def main(out):
    results = {{}}
    loads = []
    for k, case in enumerate(CASES):
        R, F = solve(case, (build_model, globals()[f"load_case_{{k + 1}}"], analysis))
        for tag, fe in FIXED_END.get(case, {{}}).items():
            F[tag] = [a + b for a, b in zip(F[tag], fe)]
        results[case] = (R, F)
        loads.append((case, "case", {first}, R, F))
    for name, kind, how, factors, model, scale in COMBINATIONS:
        if model is None:
            R, F = mix(results, factors, scale)
        else:
            R, F = solve(name, (model,), {steps})
            for case, f in factors.items():
                for tag, fe in FIXED_END.get(case, {{}}).items():
                    F[tag] = [a + f * b for a, b in zip(F[tag], fe)]
        loads.append((name, kind, how, R, F))
    num = lambda v: format(v, {digits})  # noqa: E731
    with open(os.path.join(out, "structure_model_reactions.csv"), "w", newline="", encoding="utf-8") as fh:
        fh.write(REACTION_NOTE + "\\n")
        w = csv.writer(fh)
        w.writerow(REACTION_COLUMNS)
        for name, kind, how, R, _ in loads:
            for nid, tag, _ in SUPPORTS:
                w.writerow([name, kind, how, "", nid, tag] + [num(v) for v in COORDINATES[tag]]
                           + [num(v * 1e-3) for v in R[tag][:3]] + [num(v * 1e-6) for v in R[tag][3:]])
    with open(os.path.join(out, "structure_model_member_forces.csv"), "w", newline="", encoding="utf-8") as fh:
        fh.write(MEMBER_NOTE + "\\n")
        w = csv.writer(fh)
        w.writerow(MEMBER_COLUMNS)
        for name, kind, how, _, F in loads:
            for bid, tag, ni, nj in BEAMS:
                for end, node, cols in (("i", ni, F[tag][:6]), ("j", nj, F[tag][6:])):
                    w.writerow([name, kind, how, "", bid, tag, end, node] + [num(v * 1e-3) for v in cols[:3]]
                               + [num(v * 1e-6) for v in cols[3:]])
    print(f"{{len(CASES)}} cases, {{len(COMBINATIONS)}} combinations: structure_model_reactions.csv and "
          f"structure_model_member_forces.csv in {{out}}")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else os.path.dirname(os.path.abspath(__file__)))
'''


def write_exchange(check, folder, name: str = "") -> dict[str, dict]:
    """Write ``reactions.csv``, ``member_forces.csv`` and ``structure_model.py`` of ``check`` (a
    StructureCheck) into ``folder`` (atomic); ``{file name: facts}`` for the run's file list."""
    from optimize.atomic import atomic_open
    from optimize.errors import write_error

    folder = Path(folder)
    files = {REACTIONS: _write_csv(folder / REACTIONS, REACTION_NOTE, REACTION_COLUMNS, reaction_rows(check),
                                   "reactions"),
             MEMBER_FORCES: _write_csv(folder / MEMBER_FORCES, MEMBER_NOTE, MEMBER_COLUMNS, member_rows(check),
                                       "member end forces")}
    t0 = time.perf_counter()
    path = folder / SCRIPT
    text = model_script(check, name)
    try:
        with atomic_open(path, "w", encoding="utf-8") as fh:
            fh.write(text)
    except OSError as exc:
        raise write_error(path, "structure model script", exc) from exc
    files[SCRIPT] = {"file": SCRIPT, "bytes": path.stat().st_size, "seconds": time.perf_counter() - t0,
                     "what": "the analysis model as an OpenSees (openseespy) script, N and mm"}
    files[REACTIONS]["what"] = "support reactions per load case and combination, kN and kNm"
    files[MEMBER_FORCES]["what"] = "member end forces per load case and combination, local axes, kN and kNm"
    return files
