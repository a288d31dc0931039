"""Small structures for the CAD and export tests (surfaces of revolution: conical exactly)."""
from __future__ import annotations

import functools

import numpy as np

from optimize.modelling import shapes


def dome_mesh(n_around: int = 8, k: int = 4, radius_m: float = 6.0, rise_m: float = 2.0, sweep=2 * np.pi):
    """A dome of revolution in mm (PQ, conical and circular by construction)."""
    m = shapes.revolution(shapes.dome_profile(radius=radius_m, rise=rise_m, k=k), n_around, sweep=sweep,
                          name="dome")
    return m.with_vertices(m.V * 1000.0)


@functools.lru_cache(maxsize=None)
def dome_structure(n_around: int = 8, k: int = 4, depth: float = 200.0, flip: bool = False, sweep=2 * np.pi):
    from fabricate.offset import offset_structure

    return offset_structure(dome_mesh(n_around, k, sweep=sweep), (0.0, -depth), flip=flip)


@functools.lru_cache(maxsize=None)
def dome_parts(n_around: int = 6, k: int = 3, node_radius: float = 40.0):
    """The parts of :func:`dome_structure` with hubs: panels, beams and nodes (parts are frozen data)."""
    from fabricate.cad import PartSpec, build_parts

    return build_parts(dome_structure(n_around=n_around, k=k), PartSpec(node_radius=node_radius))


def rigid(V: np.ndarray, seed: int = 3) -> np.ndarray:
    """``V (n, 3)`` after a seeded random rotation and translation."""
    rng = np.random.default_rng(seed)
    q, _ = np.linalg.qr(rng.standard_normal((3, 3)))
    q *= np.sign(np.linalg.det(q))
    return V @ q.T + rng.uniform(-5000, 5000, 3)


def capped_dome_mesh(n_around: int = 7, k: int = 3):
    """The dome with its top ring closed by one ``n_around``-gon (mixed face sizes)."""
    from optimize.mesh import Mesh

    m = dome_mesh(n_around, k)
    faces = m.faces_list() + [[i * k + (k - 1) for i in range(n_around)]]
    return Mesh(m.V, faces, name="capped_dome")


def rezip_3mf(src, dst, edit):
    """A copy ``dst`` of the 3MF ``src`` with its model text passed through ``edit`` (bytes -> bytes)."""
    import zipfile

    with zipfile.ZipFile(src) as z:
        items = {n: z.read(n) for n in z.namelist()}
    items["3D/3dmodel.model"] = edit(items["3D/3dmodel.model"])
    with zipfile.ZipFile(dst, "w") as z:
        for n, b in items.items():
            z.writestr(n, b)
    return dst
