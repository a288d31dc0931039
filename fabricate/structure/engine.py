"""Linear static solution of a :class:`~fabricate.structure.frame.Frame` by OpenSees (openseespy).

The model is built here from our arrays; the solution is OpenSees': ``elasticBeamColumn``
elements (Euler-Bernoulli, one per beam), a ``Linear`` geometric transformation per element
whose ``vecxz`` is the beam-plane normal, the ``Mumps`` sparse direct solver (its own fill-reducing
ordering, so the ``Plain`` numberer; it reports a singular stiffness, a mechanism, as a failed
step).  Measured on a 10,000-beam dome (first step, which factors): Mumps 2.1 s, SparseSYM 3.3 s
(but it crashed the process after an MKL PARDISO optimization in the same run), SuperLU 6.3 s,
BandSPD 12.6 s, UmfPack 15 s (and it does not report a singular matrix), ProfileSPD 37 s.
Pinned joints: both bending moments released at every element end (``-releasey``/``-releasez``);
a released end does not turn its node, so the node rotations would have no stiffness but the
members' torsion (none at all where the members of a node lie in one plane): they are held (fixed)
at every node, which changes no force (the rotations are uncoupled from the translations once the
ends are released, and no load is a torque).  A pin-jointed frame needs at least one member per
free node translation (Maxwell's count; a quad grid has about two per node): fewer is named a
mechanism before solving.  Pinned frames use BandSPD with RCM numbering: on a pin-jointed quad grid
Mumps returned finite displacements where BandSPD reports the mechanism.
Support springs: a fixed ground node and a ``zeroLength`` element of ``Elastic`` materials per
sprung node; semi-rigid joints: an end node per element end (``equalDOF`` translations, rotational
springs in the element's axes); both built by :func:`build_model`, which also writes the model as a
script (:mod:`fabricate.structure.exchange`).  :func:`solve_second_order`: one combination, ``PDelta``
transformations on an imperfect geometry, Newton in load increments.
Every load case is a pattern switched on at its own step only (a ``Path``
series 0-1-0), and the ``Linear`` algorithm factors the stiffness once for all of them.
OpenSees is imported here only.

Section axes: OpenSees' local ``z`` moment of inertia is the section's strong ``Iy`` (bending
in the beam plane), its local ``y`` one the weak ``Iz``.
"""
from __future__ import annotations

import ctypes
import importlib.util
import os
import time
from dataclasses import dataclass, field

import numpy as np

from optimize.errors import ConfigError

from .frame import Frame
from .loads import LoadCase


SYSTEM = "Mumps"
"""OpenSees' linear system (see the module docstring)."""


class MechanismError(ConfigError):
    """The frame cannot carry its loads: singular stiffness (too few supports, released joints)."""


@dataclass(frozen=True, eq=False)
class Solution:
    """Results of every load case, in the order solved.

    end_forces : {case: (e, 12) float} forces and moments on each element at its ends, local axes
        ``[N1 Vy1 Vz1 T1 My1 Mz1 N2 Vy2 Vz2 T2 My2 Mz2]`` (N, N mm; OpenSees' ``localForce``).
    displacements : {case: (n, 6) float} node displacements (mm) and rotations (rad), global.
    reactions : {case: (n, 6) float} support reactions (N, N mm), global.
    line_local : {case: (e, 3) float} the element line loads in local axes (N/mm).
    seconds : {"build", "solve", "read"} time inside OpenSees calls; ``ours`` the rest.
    """

    end_forces: dict
    displacements: dict
    reactions: dict
    line_local: dict
    seconds: dict = field(default_factory=dict)
    version: str = ""


def _opensees():
    """The openseespy module; its wheel's own BLAS is loaded first (the wheel's LAPACK does not
    find it on every Linux)."""
    try:
        spec = importlib.util.find_spec("openseespylinux")
        if spec is not None and spec.origin:
            blas = os.path.join(os.path.dirname(spec.origin), "lib", "libblas.so.3")
            if os.path.exists(blas):
                ctypes.CDLL(blas, mode=ctypes.RTLD_LOCAL)
        import openseespy.opensees as ops
        _quiet_exit()
    except (ImportError, RuntimeError, OSError) as exc:
        raise RuntimeError(f"OpenSees (openseespy) cannot be imported: {exc}; install it with "
                           "pip install openseespy") from None
    return ops


_QUIET = []


def _quiet_exit() -> None:
    """OpenSees prints "Process 0 Terminating" on stderr when the interpreter exits, after our last
    line (an error message must stay one line): at exit, once everything of ours is flushed, stderr's
    file descriptor goes to the null device."""
    if _QUIET:
        return
    import atexit
    import sys

    def hush():
        try:
            sys.stdout.flush()
            sys.stderr.flush()
            fd = os.open(os.devnull, os.O_WRONLY)
            os.dup2(fd, 2)
        except (OSError, ValueError):
            pass

    atexit.register(hush)
    _QUIET.append(hush)


def pinned_count(frame: Frame) -> None:
    """Raise MechanismError when a pin-jointed ``frame`` has fewer members than free node translations
    (Maxwell's necessary count: each member holds one distance; a quad grid without diagonals has
    about two members per node for three translations)."""
    free = int(3 * frame.n_nodes - frame.fixed[:, :3].sum())
    if frame.n_elements < free:
        raise MechanismError(
            f"the pin-jointed frame is a mechanism: {frame.n_elements} beams for {free} free node translations "
            f"({frame.n_nodes} nodes, {int(frame.fixed[:, :3].any(axis=1).sum())} supported); a pinned member "
            "holds one distance, so it needs at least as many members as free translations (a quad grid has "
            "about two per node for three: it folds); expected a triangulated mesh, more supports, or "
            "rigid connections")


@dataclass(frozen=True, eq=False)
class Model:
    """What :func:`build_model` made: ``supported`` (k,) node indices with a reaction, ``ground``
    {node index: OpenSees tag of the fixed node its springs hold}, ``axes`` (e, 3, 3) local frames."""

    supported: np.ndarray
    ground: dict
    axes: np.ndarray


SPRING_TORSION = 1e3
"""Semi-rigid joints: the torsional spring between an element end and its node is this many times the
element's own G J / L (rigid in practice; only the bending rotations are semi-rigid)."""


def build_model(ops, frame: Frame, X: np.ndarray | None = None, transf: str = "Linear") -> Model:
    """Build ``frame`` in ``ops`` (OpenSees, or a recorder that writes the same calls as a script):
    nodes 1..n at ``X`` (default ``frame.X``), supports, springs (a fixed ground node per sprung node
    and a ``zeroLength`` element of ``Elastic`` materials), semi-rigid joints (an end node per element
    end, ``equalDOF`` translations, a ``zeroLength`` in the element's axes: bending springs
    ``joint_stiffness``, torsion :data:`SPRING_TORSION` x GJ/L), ``elasticBeamColumn`` elements with a
    ``transf`` (``Linear`` | ``PDelta``) geometric transformation each."""
    X = frame.X if X is None else X
    n, e = frame.n_nodes, frame.n_elements
    axes = Frame(X, frame.elements, frame.vecxz, frame.sections, frame.section_of, frame.E, frame.G,
                 frame.fixed).local_axes()
    A, Iy, Iz, J = frame.prop("A"), frame.prop("Iy"), frame.prop("Iz"), frame.prop("J")
    held = frame.fixed.copy()
    if frame.pinned:  # released ends leave the node rotations without stiffness: hold them (no force changes)
        held[:, 3:] = True
    springs = np.zeros((n, 6)) if frame.springs is None else np.where(held, 0.0, frame.springs)
    release = ["-releasez", 3, "-releasey", 3] if frame.pinned else []
    E, G = frame.E, frame.G
    ops.wipe()
    ops.model("basic", "-ndm", 3, "-ndf", 6)
    for i, (x, y, z) in enumerate(X.tolist()):
        ops.node(i + 1, x, y, z)
    fixed = held.astype(int).tolist()
    for i in np.nonzero(held.any(axis=1))[0].tolist():
        ops.fix(i + 1, *fixed[i])
    tag = n + 1
    ground, mat = {}, 0
    sprung = np.nonzero((springs > 0).any(axis=1))[0].tolist()
    for i in sprung:
        ops.node(tag, *X[i].tolist())
        ops.fix(tag, 1, 1, 1, 1, 1, 1)
        ground[i] = tag
        tag += 1
    ele = e + 1
    for i in sprung:
        dirs = np.nonzero(springs[i] > 0)[0].tolist()
        mats = []
        for d in dirs:
            mat += 1
            ops.uniaxialMaterial("Elastic", mat, float(springs[i, d]))
            mats.append(mat)
        ops.element("zeroLength", ele, ground[i], i + 1, "-mat", *mats, "-dir", *[d + 1 for d in dirs])
        ele += 1
    ends = (frame.elements + 1).tolist()
    if frame.semi_rigid:  # an end node per element end, joined to its node by rotational springs
        L = np.linalg.norm(X[frame.elements[:, 1]] - X[frame.elements[:, 0]], axis=1)
        mat += 1
        ops.uniaxialMaterial("Elastic", mat, float(frame.joint_stiffness))
        bend = mat
        for k, (a, b) in enumerate(frame.elements.tolist()):
            mat += 1
            ops.uniaxialMaterial("Elastic", mat, float(SPRING_TORSION * G * J[k] / L[k]))
            pair = []
            for node in (a, b):
                ops.node(tag, *X[node].tolist())
                ops.equalDOF(node + 1, tag, 1, 2, 3)
                ops.element("zeroLength", ele, node + 1, tag, "-mat", mat, bend, bend, "-dir", 4, 5, 6,
                            "-orient", *axes[k, 0].tolist(), *axes[k, 1].tolist())
                pair.append(tag)
                tag += 1
                ele += 1
            ends[k] = pair
    for k, ((a, b), v, (a_, iy, iz, j)) in enumerate(zip(ends, frame.vecxz.tolist(),
                                                          np.stack([A, Iy, Iz, J], axis=1).tolist())):
        ops.geomTransf(transf, k + 1, *v)
        # OpenSees: A E G J Iy(local y, weak) Iz(local z, strong)
        ops.element("elasticBeamColumn", k + 1, a, b, a_, E, G, j, iz, iy, k + 1, *release)
    supported = np.nonzero(held.any(axis=1) | (springs > 0).any(axis=1))[0]
    return Model(supported, ground, axes)


def analysis(ops, frame: Frame, *, linear: bool = True, steps: int = 1, tol: float = 1e-8) -> None:
    """The analysis objects: the linear system (see the module docstring), ``Transformation``
    constraints where joints are semi-rigid, ``LoadControl`` of ``1 / steps``, and the ``Linear``
    algorithm factoring once (``linear``) or ``Newton`` with a displacement-increment test."""
    if frame.pinned:  # released joints leave rotations free: BandSPD reports the singular matrix, Mumps may not
        ops.system("BandSPD")
        ops.numberer("RCM")
    elif frame.semi_rigid:  # equalDOF constraints: transformed, so the system is not banded-symmetric
        ops.system("UmfPack")
        ops.numberer("RCM")
    else:
        ops.system(SYSTEM)
        ops.numberer("Plain")
    ops.constraints("Transformation" if frame.semi_rigid else "Plain")
    ops.integrator("LoadControl", 1.0 / steps)
    if linear:
        ops.algorithm("Linear", "-factorOnce")
    else:
        ops.test("NormDispIncr", tol, 50)
        ops.algorithm("Newton")
    ops.analysis("Static")


def add_loads(ops, pattern: int, series: int, case: LoadCase, axes: np.ndarray) -> np.ndarray:
    """A ``Plain`` pattern of ``case`` (element line loads in local axes, nodal loads); returns the
    local line loads (e, 3)."""
    wl = np.einsum("eij,ej->ei", axes, case.line)  # local wx, wy, wz
    ops.pattern("Plain", pattern, series)
    loaded = np.nonzero(np.abs(wl).max(axis=1) > 0)[0]
    for el, (wx, wy, wz) in zip(loaded.tolist(), wl[loaded].tolist()):
        ops.eleLoad("-ele", el + 1, "-type", "-beamUniform", wy, wz, wx)
    nodal = np.nonzero(np.abs(case.nodal).max(axis=1) > 0)[0]
    for i, f in zip(nodal.tolist(), case.nodal[nodal].tolist()):
        ops.load(i + 1, *f)
    return wl


def read_reactions(ops, model: Model, n: int) -> np.ndarray:
    """(n, 6) float reactions of the supports (a sprung node: its springs' ground node's too)."""
    ops.reactions()
    R = np.zeros((n, 6))
    for i in model.supported.tolist():
        R[i] = ops.nodeReaction(i + 1)
        if i in model.ground:
            R[i] += np.asarray(ops.nodeReaction(model.ground[i]))
    return R


FRESH_MODEL = ("semi-rigid joints: every load case is solved in a model of its own, from zero; with the "
               "equalDOF-joined end nodes under the Transformation handler, a step from a loaded state (the "
               "one-factorization series of the other frames) drifts: on a dome on springs the second case came "
               "out 6 % off a separate solve and the numpy stiffness of the stability check, and re-applying a "
               "load moved it further each step")


def solve(frame: Frame, cases: dict[str, LoadCase]) -> Solution:
    """Solve ``frame`` for each case in ``cases`` (linear elastic; superposition holds).

    Semi-rigid joints: one model per case (:data:`FRESH_MODEL`).
    Raises MechanismError when the stiffness is singular or the displacements are not finite
    or larger than the frame itself, or (pinned joints) when the members are fewer than the free
    node translations.
    """
    if frame.pinned:
        pinned_count(frame)
    if frame.semi_rigid and len(cases) > 1:  # one model per case: see FRESH_MODEL
        parts = [solve(frame, {name: case}) for name, case in cases.items()]
        merged = [{k: v for p in parts for k, v in getattr(p, f).items()}
                  for f in ("end_forces", "displacements", "reactions", "line_local")]
        spent = {k: round(sum(p.seconds.get(k, 0.0) for p in parts), 4) for k in parts[0].seconds}
        return Solution(*merged, spent, parts[0].version)
    ops = _opensees()
    t0 = time.perf_counter()
    spent = {"build": 0.0, "solve": 0.0, "read": 0.0}
    t = time.perf_counter()
    ops.wipe()
    ops.logFile(os.devnull, "-noEcho")
    model = build_model(ops, frame)
    analysis(ops, frame)
    size = float(np.linalg.norm(frame.X.max(axis=0) - frame.X.min(axis=0)))
    end_forces, disp, reac, line_local = {}, {}, {}, {}
    n, e = frame.n_nodes, frame.n_elements
    steps = []
    for name, case in cases.items():  # every case is a pattern that is on (factor 1) at its own step only
        wl = np.einsum("eij,ej->ei", model.axes, case.line)
        line_local[name] = wl
        if not (np.abs(wl).max(initial=0.0) > 0 or np.abs(case.nodal).max(initial=0.0) > 0):
            end_forces[name], disp[name], reac[name] = np.zeros((e, 12)), np.zeros((n, 6)), np.zeros((n, 6))
            continue  # an empty case (a zero load): nothing to solve
        steps.append(name)
        k = len(steps)
        ops.timeSeries("Path", k, "-time", k - 1.0, k, k + 1.0, "-values", 0.0, 1.0, 0.0)
        add_loads(ops, k, k, case, model.axes)
    spent["build"] += time.perf_counter() - t
    for name in steps:  # linear: step k solves K du = P_k - K u_(k-1), so u_k = K^-1 P_k (one factorization)
        t = time.perf_counter()
        ok = ops.analyze(1)
        spent["solve"] += time.perf_counter() - t
        t = time.perf_counter()
        U = np.array([ops.nodeDisp(i + 1) for i in range(n)], dtype=float).reshape(n, 6)
        Fe = np.array([ops.eleResponse(k + 1, "localForce") for k in range(e)], dtype=float).reshape(e, 12)
        R = read_reactions(ops, model, n)
        spent["read"] += time.perf_counter() - t
        if ok != 0 or not (np.isfinite(U).all() and np.isfinite(Fe).all()) or \
                np.abs(U[:, :3]).max(initial=0.0) > max(size, 1.0):
            ops.wipe()
            why = (f"OpenSees found the stiffness singular (analyze returned {ok})" if ok != 0
                   else "the displacements are not finite or larger than the frame itself")
            raise MechanismError(f"the frame is a mechanism (or far too soft) under load case {name!r}: {why}; "
                                 f"expected supports that hold it ({len(model.supported)} supported nodes) and "
                                 f"connections that make it stiff ({joints(frame)} joints)")
        if cases[name].fixed_end is not None:
            Fe = Fe + cases[name].fixed_end
        end_forces[name], disp[name], reac[name] = Fe, U, R
    try:
        from importlib.metadata import version as _version
        version = _version("openseespy")
    except Exception:  # noqa: BLE001 - a version string is a courtesy
        version = ""
    ops.wipe()
    total = time.perf_counter() - t0
    spent = {k: round(v, 4) for k, v in spent.items()}
    spent["opensees"] = round(sum(spent.values()), 4)
    spent["ours"] = round(total - spent["opensees"], 4)
    return Solution(end_forces, disp, reac, line_local, spent, version)


def joints(frame: Frame) -> str:
    return "pinned" if frame.pinned else "semi-rigid" if frame.semi_rigid else "rigid"


SECOND_ORDER_STEPS = 10
"""Load increments of a second-order solution."""


def second_order_model(ops, frame: Frame, case: LoadCase, X: np.ndarray, steps: int = SECOND_ORDER_STEPS):
    """Build the second-order model of ``case`` on ``frame`` with its nodes at ``X`` in ``ops`` (OpenSees or
    the script recorder): ``PDelta`` transformations, the case as one pattern on a ``Linear`` series, Newton
    in ``steps`` increments.  Returns ``(Model, line_local (e, 3))``."""
    model = build_model(ops, frame, X, transf="PDelta")
    ops.timeSeries("Linear", 1)
    wl = add_loads(ops, 1, 1, case, model.axes)
    analysis(ops, frame, linear=False, steps=steps,
             tol=1e-10 * max(float(np.linalg.norm(X.max(axis=0) - X.min(axis=0))), 1.0))
    return model, wl


def solve_second_order(frame: Frame, case: LoadCase, X: np.ndarray, steps: int = SECOND_ORDER_STEPS):
    """Geometrically nonlinear (P-Delta) solution of one combined ``case`` on the frame with its nodes
    at ``X`` (an imperfect geometry): OpenSees ``PDelta`` transformations, the load in ``steps``
    increments, Newton iterations.  Returns ``(end_forces (e, 12), displacements (n, 6), reactions
    (n, 6), line_local (e, 3))``, or None when an increment does not converge (the frame is unstable
    under the combination)."""
    ops = _opensees()
    ops.wipe()
    ops.logFile(os.devnull, "-noEcho")
    model, wl = second_order_model(ops, frame, case, X, steps)
    n, e = frame.n_nodes, frame.n_elements
    for _ in range(steps):
        if ops.analyze(1) != 0:
            ops.wipe()
            return None
    U = np.array([ops.nodeDisp(i + 1) for i in range(n)], dtype=float).reshape(n, 6)
    Fe = np.array([ops.eleResponse(k + 1, "localForce") for k in range(e)], dtype=float).reshape(e, 12)
    R = read_reactions(ops, model, n)
    ops.wipe()
    if not (np.isfinite(U).all() and np.isfinite(Fe).all()):
        return None
    if case.fixed_end is not None:
        Fe = Fe + case.fixed_end
    return Fe, U, R, wl
