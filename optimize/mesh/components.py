"""Connected components of a graph given by its edges, in NumPy alone.

The topology of every mesh needs its component labels, and ``fabricate
measure`` should not wait for SciPy to load for that: labels are found by
hooking each edge's larger root under its smaller one and jumping pointers
until every edge joins one label (a few rounds, each vectorized over the edges).
"""
from __future__ import annotations

import numpy as np


def component_labels(n: int, edges: np.ndarray) -> np.ndarray:
    """(n,) int: labels ``0..k-1`` of the connected components, numbered by their smallest vertex.

    n : number of vertices; edges : (e, 2) int vertex pairs (isolated vertices are their own component).
    """
    lab = np.arange(n)
    e0, e1 = np.asarray(edges, dtype=np.int64).reshape(-1, 2).T
    while True:  # rounds of hook + pointer jumping; each round at least halves the work left
        a, b = lab[e0], lab[e1]
        if np.array_equal(a, b):
            break
        np.minimum.at(lab, np.maximum(a, b), np.minimum(a, b))
        while True:  # pointer jumping until every vertex points at a root
            up = lab[lab]
            if np.array_equal(up, lab):
                break
            lab = up
    return np.unique(lab, return_inverse=True)[1].astype(np.int64)
