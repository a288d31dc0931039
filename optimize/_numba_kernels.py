"""The numba kernels behind :mod:`optimize.kernels` (imported only when numba is installed).

Each function mirrors a NumPy expression of the package, named in its
docstring, operation for operation (no ``fastmath``), so that both paths
agree to rounding.
"""
from __future__ import annotations

import numpy as np
from numba import njit

from .tolerances import CLOSEST_TIE as TIE  # closest-point ties: the lowest triangle index wins


@njit(cache=True, inline="always")
def _cross(a0, a1, a2, b0, b1, b2):
    return a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0


@njit(cache=True)
def angles(V, vid, jac):
    """``phi (c,)`` and ``G (c, 9)`` of :func:`optimize.mesh.corners.angle_local` at ``V[vid]``.

    V : (n, 3) float.  vid : (c, 3) int (corner, next, previous).  Without ``jac``
    ``G`` is empty ``(0, 9)``."""
    c = vid.shape[0]
    phi = np.empty(c)
    G = np.empty((c if jac else 0, 9))
    for i in range(c):
        p, a, b = vid[i, 0], vid[i, 1], vid[i, 2]
        u0, u1, u2 = V[a, 0] - V[p, 0], V[a, 1] - V[p, 1], V[a, 2] - V[p, 2]
        w0, w1, w2 = V[b, 0] - V[p, 0], V[b, 1] - V[p, 1], V[b, 2] - V[p, 2]
        n0, n1, n2 = _cross(u0, u1, u2, w0, w1, w2)
        s = np.sqrt(n0 * n0 + n1 * n1 + n2 * n2)
        phi[i] = np.arctan2(s, u0 * w0 + u1 * w1 + u2 * w2)
        if not jac:
            continue
        uu = max(u0 * u0 + u1 * u1 + u2 * u2, 1e-300)
        ww = max(w0 * w0 + w1 * w1 + w2 * w2, 1e-300)
        inv = 1.0 / s if s > 0 else 0.0
        fu, fw = inv / uu, inv / ww
        g0, g1, g2 = _cross(u0, u1, u2, n0, n1, n2)
        h0, h1, h2 = _cross(n0, n1, n2, w0, w1, w2)
        g0, g1, g2 = g0 * fu, g1 * fu, g2 * fu
        h0, h1, h2 = h0 * fw, h1 * fw, h2 * fw
        G[i, 0], G[i, 1], G[i, 2] = -(g0 + h0), -(g1 + h1), -(g2 + h2)
        G[i, 3], G[i, 4], G[i, 5] = g0, g1, g2
        G[i, 6], G[i, 7], G[i, 8] = h0, h1, h2
    return phi, G


@njit(cache=True)
def dets(V, quads, jac):
    """``D (q, 4)`` and ``G (q, 4, 12)`` of :func:`optimize.terms.determinants.det_local` at ``V[quads]``.

    Without ``jac`` ``G`` is empty ``(0, 4, 12)``."""
    q = quads.shape[0]
    D = np.empty((q, 4))
    G = np.zeros((q if jac else 0, 4, 12))
    U = np.empty((4, 3))
    L = np.empty(4)
    P = np.empty((4, 3))
    R = np.empty((4, 3))
    rel = np.empty((4, 3))
    for f in range(q):
        for j in range(4):
            a, b = quads[f, j], quads[f, (j + 1) % 4]
            e0, e1, e2 = V[b, 0] - V[a, 0], V[b, 1] - V[a, 1], V[b, 2] - V[a, 2]
            ln = max(np.sqrt(e0 * e0 + e1 * e1 + e2 * e2), 1e-300)
            L[j] = ln
            U[j, 0], U[j, 1], U[j, 2] = e0 / ln, e1 / ln, e2 / ln
        for k in range(4):
            k1, k2 = (k + 1) % 4, (k + 2) % 4
            P[k, 0], P[k, 1], P[k, 2] = _cross(U[k, 0], U[k, 1], U[k, 2], U[k1, 0], U[k1, 1], U[k1, 2])
            R[k, 0], R[k, 1], R[k, 2] = _cross(U[k2, 0], U[k2, 1], U[k2, 2], U[k, 0], U[k, 1], U[k, 2])
        for j in range(4):
            j1 = (j + 1) % 4
            D[f, j] = U[j, 0] * P[j1, 0] + U[j, 1] * P[j1, 1] + U[j, 2] * P[j1, 2]
        if not jac:
            continue
        for j in range(4):
            j1, j2 = (j + 1) % 4, (j + 2) % 4
            d = D[f, j]
            for x in range(3):
                A_ = (P[j1, x] - d * U[j, x]) / L[j]
                B_ = (R[j, x] - d * U[j1, x]) / L[j1]
                C_ = (P[j, x] - d * U[j2, x]) / L[j2]
                rel[0, x], rel[1, x], rel[2, x], rel[3, x] = -A_, A_ - B_, B_ - C_, C_
            for t in range(4):
                v = (j + t) % 4
                for x in range(3):
                    G[f, j, 3 * v + x] = rel[t, x]
    return D, G


@njit(cache=True)
def _closest_on_triangle(p0, p1, p2, a0, a1, a2, b0, b1, b2, c0, c1, c2):
    """One case of :func:`optimize.proximity.surface.closest_on_triangles` (the same branch order)."""
    ab0, ab1, ab2 = b0 - a0, b1 - a1, b2 - a2
    ac0, ac1, ac2 = c0 - a0, c1 - a1, c2 - a2
    ap0, ap1, ap2 = p0 - a0, p1 - a1, p2 - a2
    d1 = ab0 * ap0 + ab1 * ap1 + ab2 * ap2
    d2 = ac0 * ap0 + ac1 * ap1 + ac2 * ap2
    bp0, bp1, bp2 = p0 - b0, p1 - b1, p2 - b2
    d3 = ab0 * bp0 + ab1 * bp1 + ab2 * bp2
    d4 = ac0 * bp0 + ac1 * bp1 + ac2 * bp2
    cp0, cp1, cp2 = p0 - c0, p1 - c1, p2 - c2
    d5 = ab0 * cp0 + ab1 * cp1 + ab2 * cp2
    d6 = ac0 * cp0 + ac1 * cp1 + ac2 * cp2
    vc = d1 * d4 - d3 * d2
    vb = d5 * d2 - d1 * d6
    va = d3 * d6 - d5 * d4
    if d1 <= 0 and d2 <= 0:
        return a0, a1, a2
    if d3 >= 0 and d4 <= d3:
        return b0, b1, b2
    if vc <= 0 and d1 >= 0 and d3 <= 0:
        den = d1 - d3
        t = d1 / (den if den != 0 else 1.0)
        return a0 + t * ab0, a1 + t * ab1, a2 + t * ab2
    if d6 >= 0 and d5 <= d6:
        return c0, c1, c2
    if vb <= 0 and d2 >= 0 and d6 <= 0:
        den = d2 - d6
        t = d2 / (den if den != 0 else 1.0)
        return a0 + t * ac0, a1 + t * ac1, a2 + t * ac2
    if va <= 0 and (d4 - d3) >= 0 and (d5 - d6) >= 0:
        den = (d4 - d3) + (d5 - d6)
        t = (d4 - d3) / (den if den != 0 else 1.0)
        return b0 + t * (c0 - b0), b1 + t * (c1 - b1), b2 + t * (c2 - b2)
    den = va + vb + vc
    den = den if den != 0 else 1.0
    v, w = vb / den, vc / den
    return a0 + v * ab0 + w * ac0, a1 + v * ab1 + w * ac1, a2 + v * ab2 + w * ac2


@njit(cache=True)
def closest_candidates(P, A, B, C, owner, cand, skip, lo, hi, prev):
    """Nearest candidate of every point: ``Y (q, 3)``, ``tri (q,)``, ``found (q,)`` bool.

    P : (q, 3).  A, B, C : (t, 3) triangle corners, ``lo, hi (t, 3)`` their
    bounding boxes.  owner, cand : (m,) int, pairs (point, triangle) sorted by
    point.  skip : (q,) bool, points to leave out.  prev : (q,) int, a
    triangle tried first for each point (its last closest one; -1: none): a
    candidate whose box is farther than the best distance so far cannot be
    closer and is not tested.  Squared distances are compared, as in
    ``Footpoints._pick``; of triangles within ``TIE`` of the closest the lowest index wins."""
    q = P.shape[0]
    Y = np.empty((q, 3))
    tri = np.full(q, -1, dtype=np.int64)
    best = np.full(q, np.inf)
    for o in range(q):
        f = prev[o]
        if skip[o] or f < 0:
            continue
        y0, y1, y2 = _closest_on_triangle(P[o, 0], P[o, 1], P[o, 2], A[f, 0], A[f, 1], A[f, 2],
                                          B[f, 0], B[f, 1], B[f, 2], C[f, 0], C[f, 1], C[f, 2])
        e0, e1, e2 = y0 - P[o, 0], y1 - P[o, 1], y2 - P[o, 2]
        best[o] = e0 * e0 + e1 * e1 + e2 * e2
        Y[o, 0], Y[o, 1], Y[o, 2] = y0, y1, y2
        tri[o] = f
    for k in range(owner.shape[0]):
        o = owner[k]
        f = cand[k]
        if skip[o] or f == prev[o]:
            continue
        p0, p1, p2 = P[o, 0], P[o, 1], P[o, 2]
        b0 = max(max(lo[f, 0] - p0, p0 - hi[f, 0]), 0.0)
        b1 = max(max(lo[f, 1] - p1, p1 - hi[f, 1]), 0.0)
        b2 = max(max(lo[f, 2] - p2, p2 - hi[f, 2]), 0.0)
        b = best[o]
        if b0 * b0 + b1 * b1 + b2 * b2 > b * (1 + TIE):
            continue
        y0, y1, y2 = _closest_on_triangle(p0, p1, p2, A[f, 0], A[f, 1], A[f, 2],
                                          B[f, 0], B[f, 1], B[f, 2], C[f, 0], C[f, 1], C[f, 2])
        e0, e1, e2 = y0 - p0, y1 - p1, y2 - p2
        d = e0 * e0 + e1 * e1 + e2 * e2
        if tri[o] < 0 or d < b * (1 - TIE) or (d <= b * (1 + TIE) and f < tri[o]):
            best[o] = d
            Y[o, 0], Y[o, 1], Y[o, 2] = y0, y1, y2
            tri[o] = f
    return Y, tri, tri >= 0


@njit(cache=True)
def interpolated_normals(Y, tri, A, B, C, T, vn, fn):
    """(k, 3) unit normals at footpoints ``Y (k, 3)`` on triangles ``tri (k,)``:
    ``optimize.proximity.surface.Reference._interpolated_normals`` (triangles ``T (t, 3)``,
    vertex normals ``vn (n, 3)``, triangle normals ``fn (t, 3)``)."""
    k = Y.shape[0]
    N = np.empty((k, 3))
    for i in range(k):
        f = tri[i]
        e00, e01, e02 = B[f, 0] - A[f, 0], B[f, 1] - A[f, 1], B[f, 2] - A[f, 2]
        e10, e11, e12 = C[f, 0] - A[f, 0], C[f, 1] - A[f, 1], C[f, 2] - A[f, 2]
        e20, e21, e22 = Y[i, 0] - A[f, 0], Y[i, 1] - A[f, 1], Y[i, 2] - A[f, 2]
        d00 = e00 * e00 + e01 * e01 + e02 * e02
        d01 = e00 * e10 + e01 * e11 + e02 * e12
        d11 = e10 * e10 + e11 * e11 + e12 * e12
        d20 = e20 * e00 + e21 * e01 + e22 * e02
        d21 = e20 * e10 + e21 * e11 + e22 * e12
        den = d00 * d11 - d01 * d01
        ok = den > 1e-14 * max(d00 * d11, 1e-300)
        if not ok:
            den = 1.0
        v = (d11 * d20 - d01 * d21) / den
        w = (d00 * d21 - d01 * d20) / den
        a, b, c = T[f, 0], T[f, 1], T[f, 2]
        u = 1 - v - w
        n0 = u * vn[a, 0] + v * vn[b, 0] + w * vn[c, 0]
        n1 = u * vn[a, 1] + v * vn[b, 1] + w * vn[c, 1]
        n2 = u * vn[a, 2] + v * vn[b, 2] + w * vn[c, 2]
        ln = np.sqrt(n0 * n0 + n1 * n1 + n2 * n2)
        if ok and ln > 1e-6:
            N[i, 0], N[i, 1], N[i, 2] = n0 / ln, n1 / ln, n2 / ln
        else:
            N[i, 0], N[i, 1], N[i, 2] = fn[f, 0], fn[f, 1], fn[f, 2]
    return N


@njit(cache=True)
def group_gram(a, starts, m, ii, jj, dest, out):
    """``out[dest[G, t]] += sum_r a[starts[G, r] + ii[t]] * a[starts[G, r] + jj[t]]`` (in place).

    The Gram matrices of groups of CSR rows with the same ``m`` columns, pair
    ``t = (ii[t], jj[t])`` of the upper triangle (``ii <= jj``; it is symmetric);
    ``starts (G, g)`` is where each row's values begin in ``a``.  ``RowGram.values``
    for one class of groups."""
    G, g = starts.shape
    block = np.empty((g, m))
    for grp in range(G):
        for r in range(g):
            st = starts[grp, r]
            for c in range(m):
                block[r, c] = a[st + c]
        for t in range(ii.shape[0]):
            i, j = ii[t], jj[t]
            s = 0.0
            for r in range(g):
                s += block[r, i] * block[r, j]
            out[dest[grp, t]] += s


@njit(cache=True)
def ldl_factor(L, positive, ext):
    """In place: ``M = L D L^T`` without pivoting of a symmetric band ``L (n, bw + 1)``
    (C order), ``L[j, d] = M[j + d, j]``; afterwards ``L[j, 0] = D_j`` and ``L[j, d]``
    the unit lower factor's entries.  ``ext (n,)``: column ``j`` of ``M`` and of its
    factor has no entry below row ``j + ext[j]`` (the envelope, which the factorization
    does not leave: ``BandOrder.ext``).  Returns False at a zero or non-finite pivot,
    or, with ``positive``, at a pivot ``<= 0`` (``M`` is not positive definite to
    working precision, where LAPACK's ``dpbtrf`` fails too)."""
    n, m1 = L.shape
    bw = m1 - 1
    col = np.empty(m1)
    Lf = L.ravel()  # a view: the updates below are contiguous slices of it
    for j in range(n):
        d = Lf[j * m1]
        if d == 0.0 or not np.isfinite(d) or (positive and d < 0.0):
            return False
        lim = min(ext[j], bw, n - 1 - j)
        inv = 1.0 / d
        for i in range(lim + 1):
            col[i] = Lf[j * m1 + i]
        for k in range(1, lim + 1):
            lk = col[k] * inv
            base = (j + k) * m1 - k  # row j + k, slot i - k
            seg = Lf[base + k: base + lim + 1]
            src = col[k: lim + 1]
            for i in range(seg.shape[0]):
                seg[i] -= src[i] * lk
        for i in range(1, lim + 1):
            Lf[j * m1 + i] = col[i] * inv
    return True


@njit(cache=True)
def ldl_solve(L, b, ext):
    """(n,) float: ``M^{-1} b`` for the factor of :func:`ldl_factor` (``b`` is not changed)."""
    n, m1 = L.shape
    bw = m1 - 1
    y = b.copy()
    for j in range(n):
        lim = min(ext[j], bw, n - 1 - j)
        yj = y[j]
        for i in range(1, lim + 1):
            y[j + i] -= L[j, i] * yj
    for j in range(n):
        y[j] /= L[j, 0]
    for j in range(n - 1, -1, -1):
        lim = min(ext[j], bw, n - 1 - j)
        s = y[j]
        for i in range(1, lim + 1):
            s -= L[j, i] * y[j + i]
        y[j] = s
    return y


@njit(cache=True)
def quad_planarity_max(V, quads):
    """``optimize.mesh.measures.quad_planarity(V[quads]).max(initial=0)``: the largest
    diagonal-line distance / mean diagonal length over the quads ``quads (q, 4)``."""
    out = 0.0
    for f in range(quads.shape[0]):
        a, b, c, d = quads[f, 0], quads[f, 1], quads[f, 2], quads[f, 3]
        p0, p1, p2 = V[c, 0] - V[a, 0], V[c, 1] - V[a, 1], V[c, 2] - V[a, 2]
        q0, q1, q2 = V[d, 0] - V[b, 0], V[d, 1] - V[b, 1], V[d, 2] - V[b, 2]
        n0, n1, n2 = _cross(p0, p1, p2, q0, q1, q2)
        nn = np.sqrt(n0 * n0 + n1 * n1 + n2 * n2)
        l1 = np.sqrt(p0 * p0 + p1 * p1 + p2 * p2)
        l2 = np.sqrt(q0 * q0 + q1 * q1 + q2 * q2)
        g0, g1, g2 = V[b, 0] - V[a, 0], V[b, 1] - V[a, 1], V[b, 2] - V[a, 2]
        if nn > 1e-12 * l1 * l2:
            dist = abs(g0 * n0 + g1 * n1 + g2 * n2) / nn
        else:
            m0, m1, m2 = _cross(g0, g1, g2, p0, p1, p2)
            dist = np.sqrt(m0 * m0 + m1 * m1 + m2 * m2) / max(l1, 1e-300)
        val = dist / (0.5 * (l1 + l2))
        if val > out or not val == val:
            out = val
            if not val == val:
                return val
    return out


@njit(cache=True)
def scan_triangles(P, idx, t0, margin, slack, A, B, C, lo, hi):
    """Candidate triangles of the points ``idx (k,)`` by testing every triangle.

    A triangle is a candidate of point ``i = idx[s]`` when its exact distance to
    ``P[i]`` is at most ``reach = (u + 2 margin) (1 + 1e-9) + slack``, ``u`` the
    distance to triangle ``t0[s]`` (its bounding box ``lo, hi (t, 3)`` is tested
    first; ``Footpoints._renew``).  Returns ``owner, cand (m,)`` sorted by owner,
    then triangle, and every point's closest point ``Y (k, 3)`` and triangle
    ``tri (k,)`` among those passing the box test (the lowest index within ``TIE``)."""
    k, t = idx.shape[0], A.shape[0]
    reach = np.empty(k)
    for s in range(k):
        i, f = idx[s], t0[s]
        y0, y1, y2 = _closest_on_triangle(P[i, 0], P[i, 1], P[i, 2], A[f, 0], A[f, 1], A[f, 2],
                                          B[f, 0], B[f, 1], B[f, 2], C[f, 0], C[f, 1], C[f, 2])
        e0, e1, e2 = y0 - P[i, 0], y1 - P[i, 1], y2 - P[i, 2]
        reach[s] = (np.sqrt(e0 * e0 + e1 * e1 + e2 * e2) + 2 * margin) * (1 + 1e-9) + slack
    cap = max(16, 16 * k)
    owner = np.empty(cap, dtype=np.int64)
    cand = np.empty(cap, dtype=np.int64)
    Y = np.empty((k, 3))
    tri = np.full(k, -1, dtype=np.int64)
    m = 0
    for s in range(k):
        i = idx[s]
        p0, p1, p2 = P[i, 0], P[i, 1], P[i, 2]
        r = reach[s]
        r2 = r * r * (1 + 1e-9)
        best = np.inf
        for f in range(t):
            b0 = max(max(lo[f, 0] - p0, p0 - hi[f, 0]), 0.0)
            b1 = max(max(lo[f, 1] - p1, p1 - hi[f, 1]), 0.0)
            b2 = max(max(lo[f, 2] - p2, p2 - hi[f, 2]), 0.0)
            if b0 * b0 + b1 * b1 + b2 * b2 > r2:
                continue
            y0, y1, y2 = _closest_on_triangle(p0, p1, p2, A[f, 0], A[f, 1], A[f, 2],
                                              B[f, 0], B[f, 1], B[f, 2], C[f, 0], C[f, 1], C[f, 2])
            e0, e1, e2 = y0 - p0, y1 - p1, y2 - p2
            d = e0 * e0 + e1 * e1 + e2 * e2
            if tri[s] < 0 or d < best * (1 - TIE) or (d <= best * (1 + TIE) and f < tri[s]):
                best = d
                Y[s, 0], Y[s, 1], Y[s, 2] = y0, y1, y2
                tri[s] = f
            if np.sqrt(d) <= r:
                if m == cap:
                    cap *= 2
                    o2 = np.empty(cap, dtype=np.int64)
                    c2 = np.empty(cap, dtype=np.int64)
                    o2[:m] = owner[:m]
                    c2[:m] = cand[:m]
                    owner, cand = o2, c2
                owner[m] = i
                cand[m] = f
                m += 1
    return owner[:m], cand[:m], Y, tri


@njit(cache=True)
def scatter_rows(data, dest, coef, src, idx):
    """In place: ``data[dest[e, t]] += coef[e] * src[idx[e], t]`` where ``dest >= 0``, in the
    order of ``e`` and ``t`` (as ``np.bincount`` over the flattened triplets): a constraint
    term's Jacobian values summed into CSR data (``ConstraintSystem.evaluate_data``)."""
    m, w = dest.shape
    for e in range(m):
        c = coef[e]
        r = idx[e]
        for t in range(w):
            d = dest[e, t]
            if d >= 0:
                data[d] += c * src[r, t]


@njit(cache=True)
def csr_matvec(indptr, indices, data, x):
    """``M @ x`` for the CSR matrix ``(data, indices, indptr)`` (summed in storage order)."""
    r = indptr.shape[0] - 1
    out = np.zeros(r)
    for i in range(r):
        s = 0.0
        for t in range(indptr[i], indptr[i + 1]):
            s += data[t] * x[indices[t]]
        out[i] = s
    return out
