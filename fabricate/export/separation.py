"""Broad and narrow phase of the intersection check on parts read back: box pairs, separating planes.

A roof with welded sections mixes parts of very different sizes (5 mm plates
a metre and a half long, hub tubes, caps, glass plies), and their meshes
differ as much (a plate has 8 corners, a 24-gon tube 96).  Both phases
therefore work by classes:

- :func:`overlapping_boxes`: every box is put in a power-of-two size class
  (its largest extent); the boxes of a class are hashed into a grid of cells
  as large as the class's boxes (so a box meets at most 2 x 2 x 2 cells), and
  the boxes of every smaller or equal class are looked up in that grid.  A
  pair is kept in the one cell holding the lower corner of the two boxes'
  common box, so no pair comes twice.
- :func:`separated`: the pairs are bucketed by the plane count of the first
  part and the corner count of the second (rounded up to a power of two
  above 32), and every bucket is padded to its own size only.
"""
from __future__ import annotations

import numpy as np

EXACT_UP_TO = 32
"""Plane and corner counts up to this are buckets of their own; larger ones round up to a power of two."""


def _pairs_in_cells(key_a: np.ndarray, key_b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Every ``(i, j)`` with ``key_a[i] == key_b[j]``: ``(q,)`` indices into ``key_a`` and ``key_b``."""
    order = np.argsort(key_b, kind="stable")
    kb = key_b[order]
    start = np.searchsorted(kb, key_a, side="left")
    count = np.searchsorted(kb, key_a, side="right") - start
    i = np.repeat(np.arange(len(key_a)), count)
    j = np.repeat(start - np.cumsum(count) + count, count) + np.arange(int(count.sum()))
    return i, order[j]


def _cell_entries(lo: np.ndarray, hi: np.ndarray, size: float, origin: np.ndarray, dims: np.ndarray):
    """The grid cells (edge ``size``) every box ``lo, hi (m, 3)`` meets (at most 8 when its extent is at
    most ``size``): ``(box index (q,), cell key (q,) int64)``."""
    c0 = np.floor((lo - origin) / size).astype(np.int64)
    c1 = np.floor((hi - origin) / size).astype(np.int64)
    box, key = [], []
    for d in np.ndindex(2, 2, 2):
        c = c0 + np.array(d)
        ok = (c <= c1).all(axis=1)
        box.append(np.flatnonzero(ok))
        c = c[ok]
        key.append((c[:, 0] * dims[1] + c[:, 1]) * dims[2] + c[:, 2])
    return np.concatenate(box), np.concatenate(key)


def overlapping_boxes(lo: np.ndarray, hi: np.ndarray, pad: float = 0.0) -> np.ndarray:
    """``(q, 2)`` int pairs ``i < j`` (sorted) whose boxes ``lo, hi (p, 3)`` overlap, touching included,
    after growing every box by ``pad`` (``lo_i <= hi_j + pad`` and ``lo_j <= hi_i + pad`` on every axis).

    Boxes in power-of-two size classes, each class hashed into a grid of its own size, every class
    looked up in the grids of the classes at least as large (see the module docstring).
    """
    lo = np.asarray(lo, dtype=float).reshape(-1, 3)
    hi = np.asarray(hi, dtype=float).reshape(-1, 3) + pad
    p = len(lo)
    if p < 2:
        return np.zeros((0, 2), dtype=np.int64)
    ext = (hi - lo).max(axis=1)
    origin = lo.min(axis=0)
    span = float((hi.max(axis=0) - origin).max())
    base = max(float(ext.min()), span / 2.0 ** 20, 1e-300)      # at most 2^20 cells along an axis
    cls = np.maximum(np.ceil(np.log2(np.maximum(ext, base) / base)).astype(np.int64), 0)
    while (base * 2.0 ** cls < ext).any():                       # round-off in log2: the class holds the box
        cls = np.where(base * 2.0 ** cls < ext, cls + 1, cls)
    levels = np.unique(cls)
    members = {int(c): np.flatnonzero(cls == c) for c in levels}
    out_i, out_j = [], []
    for big in levels.tolist():
        size = base * 2.0 ** big
        dims = np.floor(span / size).astype(np.int64) + 2
        dims = np.array([dims] * 3)
        B = members[big]
        b_box, b_key = _cell_entries(lo[B], hi[B], size, origin, dims)
        for small in levels[levels <= big].tolist():
            S = members[small]
            s_box, s_key = (b_box, b_key) if small == big else _cell_entries(lo[S], hi[S], size, origin, dims)
            ia, ib = _pairs_in_cells(s_key, b_key)
            i, j, cell = S[s_box[ia]], B[b_box[ib]], s_key[ia]
            keep = (i < j) if small == big else np.ones(len(i), bool)
            i, j, cell = i[keep], j[keep], cell[keep]
            for ax in range(3):                                  # the exact test, one axis at a time
                ok = (lo[i, ax] <= hi[j, ax]) & (lo[j, ax] <= hi[i, ax])
                i, j, cell = i[ok], j[ok], cell[ok]
            ref = np.floor((np.maximum(lo[i], lo[j]) - origin) / size).astype(np.int64)
            own = (ref[:, 0] * dims[1] + ref[:, 1]) * dims[2] + ref[:, 2] == cell   # the pair's one cell
            out_i.append(i[own])
            out_j.append(j[own])
    i, j = np.concatenate(out_i), np.concatenate(out_j)
    a, b = np.minimum(i, j), np.maximum(i, j)
    order = np.lexsort((b, a))
    return np.stack([a[order], b[order]], axis=1)


def _size_class(n: np.ndarray) -> np.ndarray:
    """Bucket sizes: ``n`` itself up to :data:`EXACT_UP_TO`, else the next power of two."""
    n = np.maximum(np.asarray(n, dtype=np.int64), 1)
    pow2 = 2 ** np.ceil(np.log2(n)).astype(np.int64)
    return np.where(n <= EXACT_UP_TO, n, pow2)


def _padded(items: list[tuple[np.ndarray, np.ndarray | None]], cls: np.ndarray):
    """Per size class, the stacked padded arrays of ``items`` and each item's row in its class.

    items : ``[(X (k, 3), c (k,) or None)]``: planes (normals, offsets: padding offset +inf, a plane
    that separates nothing) or corners (``c`` None: padding repeats the first corner).
    Returns ``({class: (X (m, class, 3), c (m, class) or None)}, row (len(items),))``.
    """
    row = np.zeros(len(items), dtype=np.int64)
    out = {}
    for k in np.unique(cls).tolist():
        ix = np.flatnonzero(cls == k)
        row[ix] = np.arange(len(ix))
        X = np.zeros((len(ix), k, 3))
        C = np.full((len(ix), k), np.inf) if items[ix[0]][1] is not None else None
        for r, i in enumerate(ix.tolist()):
            x, c = items[i]
            X[r, :len(x)] = x
            if C is None:
                X[r, len(x):] = x[0]
            else:
                C[r, :len(c)] = c
        out[k] = (X, C)
    return out, row


def separated(planes: list[tuple[np.ndarray, np.ndarray]], corners: list[np.ndarray], a: np.ndarray,
              b: np.ndarray, tol: float) -> np.ndarray:
    """``(q,) bool``: one of the planes ``planes[a]`` (``(normals (k, 3), offsets (k,))``, outward) has
    every corner ``corners[b] (m, 3)`` on or outside it (within ``tol``), for every pair at once.

    Pairs bucketed by the size classes of ``planes[a]`` and ``corners[b]`` (module docstring)."""
    out = np.zeros(len(a), bool)
    if not len(a):
        return out
    used = np.unique(np.concatenate([a, b]))
    k = np.full(max(len(planes), len(corners)), -1, np.int64)
    k[used] = np.arange(len(used))
    pl = [planes[i] for i in used.tolist()]
    vx = [(corners[i], None) for i in used.tolist()]
    pcls = _size_class([len(n) for n, _ in pl])
    vcls = _size_class([len(v) for v, _ in vx])
    P, prow = _padded(pl, pcls)
    Q, vrow = _padded(vx, vcls)
    a, b = k[a], k[b]
    bucket = pcls[a] * (int(vcls.max()) + 1) + vcls[b]
    for key in np.unique(bucket).tolist():
        sel = np.flatnonzero(bucket == key)
        pc, vc = int(pcls[a[sel[0]]]), int(vcls[b[sel[0]]])
        Np, Cp = P[pc]
        Vp = Q[vc][0]
        ra, rb = prow[a[sel]], vrow[b[sel]]
        step = max(1, 65_536 // (pc * vc))                  # temporaries that stay in cache
        for s in range(0, len(sel), step):                 # chunks of pairs: bounded memory
            sa, sb = ra[s:s + step], rb[s:s + step]
            d = np.matmul(Np[sa], Vp[sb].transpose(0, 2, 1)) - Cp[sa][:, :, None]
            out[sel[s:s + step]] = (d.min(axis=2) >= -tol).any(axis=1)
    return out
