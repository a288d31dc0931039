"""Stability of the frame: the elastic critical load factor alpha_cr and its buckling modes (linear
buckling analysis), and the imperfection of a second-order analysis (EN 1993-1-1 5.2.1, 5.3.2(11)).

OpenSees has no buckling eigen-solver for frames, so the problem is assembled here: the elastic
stiffness ``K_e`` and the geometric stiffness ``K_g(N)`` of every element (the 3D Euler-Bernoulli
beam-column with cubic shape functions, McGuire, Gallagher & Ziemian, *Matrix Structural Analysis*
2nd ed., eqs. 4.34 and 9.18; ``K_g`` has the torsional term ``N (Iy + Iz) / (A L)``) under the axial
forces ``N`` of a combination of the linear solution, each beam cut into :data:`SUBDIVISIONS`
elements so that a beam buckling between its nodes is found (one cubic element over-estimates the
Euler load of a pinned strut by 22 %, four by 0.03 %).  ``(K_e + alpha K_g) phi = 0``: the
smallest positive ``alpha`` is ``alpha_cr``; solved as ``-K_g phi = mu K_e phi`` for the largest
``mu = 1 / alpha`` (scipy ``eigsh`` in ``K_e``'s inner product, ``K_e`` factored once by SuperLU;
dense ``eigh`` for small frames).

Joints and supports as the linear model has them: a pinned joint (``Frame.pinned``) gives each
element end its own two bending rotations (hinge dofs; the node rotations are held, as in
:mod:`~fabricate.structure.engine`), a semi-rigid one joins those to the node's rotation by a
rotational spring ``joint_stiffness``; support springs add to the diagonal.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from .frame import Frame

SUBDIVISIONS = 4
"""Elements per beam in the buckling analysis."""
ALPHA_CR_LIMIT = 10.0
"""EN 1993-1-1 5.2.1(3): first-order analysis may be used when alpha_cr >= 10 (elastic analysis)."""
DENSE = 600
"""Free dofs up to which the eigenproblem is solved dense."""
TOL = 1e-6
"""Relative accuracy of the eigenvalues (ARPACK)."""
MAX_RESTARTS = 30
"""ARPACK restarts before the compression-only lower bound is taken (a converging case needs about 5)."""


@dataclass(frozen=True, eq=False)
class Buckling:
    """The buckling modes of one load combination.

    alphas : (k,) float critical load factors, ascending (inf: nothing is compressed).
    X : (m, 3) float nodes of the subdivided frame (the frame's n nodes first); elements (s, 2) int.
    modes : (k, m, 3) float node translations of each mode, largest translation 1.
    lower_bound : the tension was left out (the eigen-solver did not converge with it): alphas are lower bounds.
    """

    alphas: np.ndarray
    X: np.ndarray
    elements: np.ndarray
    modes: np.ndarray
    lower_bound: bool = False

    @property
    def alpha_cr(self) -> float:
        return float(self.alphas[0]) if len(self.alphas) else float("inf")


def local_matrices(L, A, Iy, Iz, J, E, G, N):
    """``(K_e, K_g)`` (s, 12, 12) float in the local axes of ``s`` elements (dofs ``u v w rx ry rz``
    at each end; ``Iz`` bends in the local x-y plane, ``Iy`` in x-z; ``N`` + tension, N)."""
    s = len(L)
    Ke = np.zeros((s, 12, 12))
    Kg = np.zeros((s, 12, 12))

    def put(K, idx, M):
        for a, i in enumerate(idx):
            for b, j in enumerate(idx):
                K[:, i, j] += M[a][b]

    ea, gj = E * A / L, G * J / L
    put(Ke, (0, 6), [[ea, -ea], [-ea, ea]])
    put(Ke, (3, 9), [[gj, -gj], [-gj, gj]])
    for I, idx, sg in ((Iz, (1, 5, 7, 11), 1.0), (Iy, (2, 4, 8, 10), -1.0)):
        c = E * I / L ** 3
        m = [[12 * c, sg * 6 * c * L, -12 * c, sg * 6 * c * L],
             [sg * 6 * c * L, 4 * c * L ** 2, -sg * 6 * c * L, 2 * c * L ** 2],
             [-12 * c, -sg * 6 * c * L, 12 * c, -sg * 6 * c * L],
             [sg * 6 * c * L, 2 * c * L ** 2, -sg * 6 * c * L, 4 * c * L ** 2]]
        put(Ke, idx, m)
        p = N / L
        g = [[1.2 * p, sg * 0.1 * p * L, -1.2 * p, sg * 0.1 * p * L],
             [sg * 0.1 * p * L, 2 * p * L ** 2 / 15, -sg * 0.1 * p * L, -p * L ** 2 / 30],
             [-1.2 * p, -sg * 0.1 * p * L, 1.2 * p, -sg * 0.1 * p * L],
             [sg * 0.1 * p * L, -p * L ** 2 / 30, -sg * 0.1 * p * L, 2 * p * L ** 2 / 15]]
        put(Kg, idx, g)
    t = N * (Iy + Iz) / (A * L)
    put(Kg, (3, 9), [[t, -t], [-t, t]])
    return Ke, Kg


class Assembly:
    """The subdivided frame's dofs and element maps (independent of the loads): assemble ``K_e``
    once and ``K_g`` per set of axial forces.

    Dofs: 6 per node (the frame's n nodes, then ``SUBDIVISIONS - 1`` inner nodes per beam), then 2
    hinge rotations per element end where joints are pinned or semi-rigid.
    """

    def __init__(self, frame: Frame, subdivisions: int = SUBDIVISIONS):
        n, e, m = frame.n_nodes, frame.n_elements, subdivisions
        self.frame, self.m = frame, m
        a, b = frame.elements[:, 0], frame.elements[:, 1]
        t = np.arange(1, m) / m
        inner = frame.X[a][:, None, :] + t[None, :, None] * (frame.X[b] - frame.X[a])[:, None, :]
        self.X = np.concatenate([frame.X, inner.reshape(-1, 3)])
        ids = n + np.arange(e * (m - 1)).reshape(e, m - 1)
        chain = np.concatenate([a[:, None], ids, b[:, None]], axis=1)           # (e, m + 1)
        self.sub = np.stack([chain[:, :-1], chain[:, 1:]], axis=2).reshape(-1, 2)   # (e m, 2), beam by beam
        self.beam = np.repeat(np.arange(e), m)
        self.pos = np.tile(np.arange(m), e)                                      # index along the beam
        axes = frame.local_axes()
        self.R = axes[self.beam]                                                 # (s, 3, 3)
        self.L = np.repeat(frame.lengths() / m, m)
        hinged = frame.pinned or frame.semi_rigid
        ndof = 6 * len(self.X)
        s = len(self.sub)
        # slots: 16 per element: node a (6), hinge a (2), node b (6), hinge b (2); T: local 12 <- slots 16
        slots = np.zeros((s, 16), dtype=np.int64)
        T = np.zeros((s, 12, 16))
        self.hinge = np.zeros((e, 2, 2), dtype=np.int64)   # beam, end, (ry, rz) dof index; used when hinged
        for end, (node, off, loc) in enumerate(((self.sub[:, 0], 0, 0), (self.sub[:, 1], 8, 6))):
            slots[:, off:off + 6] = 6 * node[:, None] + np.arange(6)
            T[:, loc:loc + 3, off:off + 3] = self.R
            T[:, loc + 3:loc + 6, off + 3:off + 6] = self.R
            if hinged:
                at = self.pos == (0 if end == 0 else m - 1)
                beams = self.beam[at]
                hid = ndof + 2 * (2 * beams[:, None] + end) + np.arange(2)[None, :]
                self.hinge[beams, end] = hid
                slots[at, off + 6:off + 8] = hid
                T[at, loc + 4:loc + 6, :] = 0.0
                T[at, loc + 4, off + 6] = 1.0
                T[at, loc + 5, off + 7] = 1.0
        self.ndof = ndof + (4 * e if hinged else 0)
        self.slots, self.T = slots, T
        held = np.zeros((len(self.X), 6), dtype=bool)
        held[:n] = frame.fixed
        if frame.pinned:
            held[:n, 3:] = True
        free = np.ones(self.ndof, dtype=bool)
        free[:6 * len(self.X)] = ~held.reshape(-1)
        self.free = np.nonzero(free)[0]
        A, Iy, Iz, J = (frame.prop(k)[self.beam] for k in ("A", "Iy", "Iz", "J"))
        self.props = (A, Iy, Iz, J)
        # OpenSees' local z moment of inertia is the section's strong Iy (see engine): bending in x-y uses Iy
        Ke, _ = local_matrices(self.L, A, Iz, Iy, J, frame.E, frame.G, np.zeros(s))
        K = self._global(Ke)
        extra = []
        if frame.springs is not None:
            k = np.where(held[:n], 0.0, frame.springs).reshape(-1)
            extra.append(sp.diags(np.concatenate([k, np.zeros(self.ndof - len(k))])))
        if frame.semi_rigid:
            extra.append(self._joint_springs(axes, frame.joint_stiffness))
        for x in extra:
            K = K + x
        self.Ke = K.tocsc()[self.free][:, self.free]

    def _global(self, K_local: np.ndarray) -> sp.csr_matrix:
        Kg = np.swapaxes(self.T, 1, 2) @ K_local @ self.T
        rows = np.repeat(self.slots, 16, axis=1).reshape(-1)
        cols = np.tile(self.slots, (1, 16)).reshape(-1)
        return sp.coo_matrix((Kg.reshape(-1), (rows, cols)), shape=(self.ndof, self.ndof)).tocsr()

    def _joint_springs(self, axes: np.ndarray, k: float) -> sp.csr_matrix:
        """Rotational springs ``k`` between each element end's hinge rotations and the node's rotation
        about the same local axes (``1/2 k (theta_h - R_j . theta_node)^2``)."""
        e = self.frame.n_elements
        rows, cols, vals = [], [], []
        for end in (0, 1):
            node = self.frame.elements[:, end]
            for j in (0, 1):                        # local y, z
                g_idx = np.concatenate([self.hinge[:, end, j][:, None], 6 * node[:, None] + 3 + np.arange(3)], axis=1)
                g_val = np.concatenate([np.ones((e, 1)), -axes[:, 1 + j, :]], axis=1)
                rows.append(np.repeat(g_idx, 4, axis=1).reshape(-1))
                cols.append(np.tile(g_idx, (1, 4)).reshape(-1))
                vals.append((k * g_val[:, :, None] * g_val[:, None, :]).reshape(-1))
        return sp.coo_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                             shape=(self.ndof, self.ndof)).tocsr()

    def axial(self, F: np.ndarray, w: np.ndarray) -> np.ndarray:
        """(s,) float axial force (+ tension) at the middle of each sub-element, from the beams' end
        forces ``F (e, 12)`` and local line loads ``w (e, 3)`` (``N(x) = -(F1x + wx x)``)."""
        x = (self.pos + 0.5) * self.L
        return -(F[self.beam, 0] + w[self.beam, 0] * x)

    def Kg(self, N: np.ndarray) -> sp.csc_matrix:
        A, Iy, Iz, J = self.props
        _, Kg = local_matrices(self.L, A, Iz, Iy, J, self.frame.E, self.frame.G, N)
        return self._global(Kg).tocsc()[self.free][:, self.free]

    def buckling(self, N: np.ndarray, k: int = 3, lu=None) -> Buckling:
        """The ``k`` lowest buckling modes under the sub-element axial forces ``N (s,)``.

        When ARPACK does not converge within :data:`MAX_RESTARTS` (members in tension spread the spectrum
        far below the few compressed ones: an uplift combination), the tension is left out: the
        geometric stiffness of the compressed elements alone gives a lower bound of alpha_cr (tension
        only stiffens), marked ``lower_bound``."""
        try:
            return self._modes(N, k, lu, False)
        except spla.ArpackNoConvergence:
            return self._modes(np.minimum(N, 0.0), k, lu, True)

    def _modes(self, N: np.ndarray, k: int, lu, bound: bool) -> Buckling:
        nf = len(self.free)
        B = -self.Kg(N)
        B.eliminate_zeros()
        if B.nnz == 0 or not (N < 0).any():   # nothing compressed: no buckling
            return Buckling(np.zeros(0), self.X, self.sub, np.zeros((0, len(self.X), 3)), bound)
        if nf <= DENSE:
            mu, vec = scipy.linalg.eigh(B.toarray(), self.Ke.toarray())
            order = np.argsort(-mu)[:k]
            mu, vec = mu[order], vec[:, order]
        else:
            lu = lu or spla.splu(self.Ke)
            Minv = spla.LinearOperator((nf, nf), matvec=lu.solve, dtype=float)
            kk = min(k, nf - 2)
            mu, vec = spla.eigsh(B, k=kk, M=self.Ke, Minv=Minv, which="LA", tol=TOL, ncv=min(nf - 1, max(20, 4 * kk)),
                                 maxiter=MAX_RESTARTS, v0=np.ones(nf) / np.sqrt(nf))   # a fixed start: reproducible
            order = np.argsort(-mu)
            mu, vec = mu[order], vec[:, order]
        pos = mu > 1e-12  # alpha below 1e12: a compression; mu <= 0 where nothing is compressed
        alphas = np.where(pos, 1.0 / np.where(pos, mu, 1.0), np.inf)
        full = np.zeros((self.ndof, len(mu)))
        full[self.free] = vec
        tr = full[:6 * len(self.X)].reshape(len(self.X), 6, -1)[:, :3, :].transpose(2, 0, 1)
        big = np.linalg.norm(tr, axis=2).max(axis=1, initial=0.0)
        tr = tr / np.where(big > 0, big, 1.0)[:, None, None]
        keep = np.isfinite(alphas)
        return Buckling(alphas[keep], self.X, self.sub, tr[keep], bound)


def imperfection(frame: Frame, mode: np.ndarray, amplitude: float, direction: np.ndarray | None = None) -> np.ndarray:
    """(n, 3) float node coordinates of ``frame`` displaced along a buckling ``mode`` ((m, 3), its
    largest translation over the subdivided nodes 1) by ``amplitude`` mm (EN 1993-1-1 5.3.2(11): the
    first mode as the global and local imperfection), signed so that it follows ``direction (n, 3)``
    (the displacements of the combination) where given."""
    d = mode[:frame.n_nodes]
    if direction is not None and float(np.sum(d * direction)) < 0:
        d = -d
    return frame.X + amplitude * d
