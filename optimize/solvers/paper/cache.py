"""Problems kept per input mesh, so that a repeated run skips the symbolic work.

Building a :class:`optimize.solvers.paper.problem.Problem` is symbolic work that
depends only on the connectivity, the reference surface and the options:
constraint patterns, the band orderings and layouts of the linear systems,
the closest-point structure and its candidate triangles.  On the 336-quad
trefoil band that is some 15 ms, more than the paper's whole penalty run
(and what the iterations themselves now take).  Interactive modelling runs
the optimizer again and again on the same mesh, as the benchmarks do; the
problem is therefore kept as long as the input mesh lives (a weak
reference) and reused when the same mesh (vertex positions and faces
unchanged), reference and options come again.

Reuse is exact: a reused problem gives the result of a fresh one.  Nothing in a
Problem depends on an earlier run's iterates except value caches keyed by the
very positions they were computed at, and the closest-point search's warm start
(:class:`optimize.proximity.Footpoints`): its answers are exact for any query,
but a point equally close to two triangles may get the other one's normal, so
the warm start is reset when a problem is reused (:meth:`Problem.reset_warm_start`;
without it a second identical hybrid run on an n-gon mesh ended elsewhere).
"""
from __future__ import annotations

import contextlib
import threading

import numpy as np

from ...mesh import Mesh
from .problem import Problem

SLOT = "_paper_problems"  # the attribute of the mesh that holds its problems
REUSE = True  # False: build every problem afresh (benchmarks' baseline)
MAX_PER_MESH = 8  # distinct option sets kept per mesh
_GUARD = threading.Lock()  # around the lookups


def _fixed_key(fixed):
    if fixed is None or isinstance(fixed, str):
        return fixed
    return tuple(np.asarray(fixed, dtype=np.int64).ravel().tolist())


@contextlib.contextmanager
def problem_for(mesh: Mesh, target: str, *, reference: Mesh | None = None, fixed=None, **options):
    """``with problem_for(...) as p``: a :class:`Problem` for these arguments (those of
    ``Problem``), built or reused, and held by this run until the block ends.

    Reused only when ``mesh`` is the same object with the same vertex positions
    and faces as when it was built, ``reference`` is the same object (or None
    both times) with unchanged positions, every option is equal, and no other
    run (another thread) holds it; otherwise a new problem is built (and kept
    when there was none).
    """
    p, lock = _take(mesh, target, reference, fixed, options)
    try:
        yield p
    finally:
        if lock is not None:
            lock.release()


def _take(mesh, target, reference, fixed, options):
    """The problem and the lock this run holds on it (None: a problem nobody else sees)."""
    fresh = lambda: Problem(mesh, target, reference=reference, fixed=fixed, **options)  # noqa: E731
    if not REUSE:
        return fresh(), None
    key = (target, _fixed_key(fixed), tuple(sorted((k, options[k]) for k in options)))
    try:
        per_mesh = vars(mesh).setdefault(SLOT, {})
    except TypeError:  # no __dict__: no reuse
        return fresh(), None
    with _GUARD:
        entry = per_mesh.get(key)
        if entry is not None:
            p, V, F, ref, refV, lock = entry
            if (ref is reference and np.array_equal(V, mesh.V) and np.array_equal(F, mesh.F)
                    and (ref is None or np.array_equal(refV, ref.V))):
                if lock.acquire(blocking=False):
                    p.reset_warm_start()
                    return p, lock
                return fresh(), None
    p, lock = fresh(), threading.Lock()
    lock.acquire()
    with _GUARD:
        if len(per_mesh) >= MAX_PER_MESH:
            per_mesh.pop(next(iter(per_mesh)))
        per_mesh[key] = (p, mesh.V.copy(), mesh.F.copy(), reference,
                         None if reference is None else reference.V.copy(), lock)
    return p, lock
