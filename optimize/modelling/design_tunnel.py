"""The built-in ``tunnel`` design: a glazed tunnel that forks in two (a "pair of pants").

The surface has three open tube ends (three boundary loops) and, where the
tubes meet, irregular vertices: two of valence 3 (the middle of the junction's
roof and floor) and six of valence 5 (where the three tubes join), where the
paper's angle balance (valence 4 only) says nothing.  It is made as a
designer's quad model would be: a coarse control mesh (49 quads),

- the junction: a hexagonal prism with a vertical axis, the three side faces
  toward the tubes taken out, each hexagon split into three quads about its
  centre (the valence-3 vertices);
- each tube: rings of four control vertices (a rounded-square section)
  leaving the junction, the two branches turning toward the main tube's
  direction like the legs of a pair of trousers,

subdivided by Catmull-Clark, then made nearly planar (:func:`flatten`): every
quad planar to about 3e-5, as a modeller leaves it, but far from conical
(angle balance up to about 1.6 rad at the junction).  The defaults give
784 quads of about 0.6 m on a plan of about 17 x 15 m; the sizes are mm, like
every built-in design (``configs/meshes/tunnel.off`` is the same mesh in metres).
"""
from __future__ import annotations

import numpy as np

from ..errors import ConfigError
from ..mesh import Mesh
from .design_params import Design, int_param as _int, noisy as _noisy, pos_param as _pos

__all__ = ["control_mesh", "flatten", "tunnel"]


def _hexagon_quads(centre: int, ring: list[int]) -> list[list[int]]:
    """Three quads about ``centre`` covering the hexagon ``ring`` (6 vertex ids, in order)."""
    return [[centre, ring[2 * i], ring[2 * i + 1], ring[(2 * i + 2) % 6]] for i in range(3)]


def control_mesh(*, width: float, height: float, lengths, bend_deg: float, taper: float, rise: float,
                 rings, name: str = "tunnel") -> Mesh:
    """The coarse control mesh (mm): 2 hexagon centres, 12 junction vertices, 4 per tube ring.

    width, height : tube section at the junction (mm).
    lengths : (3,) tube lengths (main, left branch, right branch), from the junction centre (mm).
    bend_deg : how far each branch turns toward the main tube's axis along its length.
    taper : end section / junction section.
    rise : crown rise of each tube between its two ends, fraction of ``height``.
    rings : (3,) control rings per tube.

    The junction, seen from above, is a triangle whose side midpoints and corners
    are the hexagon's vertices: each hexagon quad is then a kite with right angles
    at the side midpoints (inscribed in a circle), and the tubes leave the three
    sides at 120 degrees, the main one along -x.  Faces point out of the tube.
    """
    w, h = float(width), float(height) / 2
    apothem = w / np.sqrt(3.0)  # a tube mouth is half a triangle side: w = apothem tan(60 deg)
    heading = np.radians([180.0, 60.0, -60.0])  # main, left, right
    order = [1, 0, 2]  # sides counter-clockwise seen from above: left (60), main (180), right (300)
    normal = np.stack([np.cos(heading), np.sin(heading), np.zeros(3)], axis=1)
    V = [[0.0, 0.0, h], [0.0, 0.0, -h]]  # hexagon centres: roof and floor
    top, bottom = [], []
    for i, k in enumerate(order):  # side midpoint, then the corner after it (counter-clockwise)
        nxt = normal[order[(i + 1) % 3]]
        corner = 2 * apothem * (normal[k] + nxt) / np.linalg.norm(normal[k] + nxt)
        for p in (apothem * normal[k], corner):
            top.append(len(V))
            V.append(p + [0.0, 0.0, h])
            bottom.append(len(V))
            V.append(p - [0.0, 0.0, h])
    F = _hexagon_quads(0, top) + [f[::-1] for f in _hexagon_quads(1, bottom)]
    for s in (1, 3, 5):  # the side quads that stay, each on the half side after a corner
        F.append([top[(s + 1) % 6], top[s], bottom[s], bottom[(s + 1) % 6]])
    turn = np.radians(bend_deg) * np.array([0.0, -1.0, 1.0])  # branches turn toward +x
    for i, k in enumerate(order):  # each tube from its mouth: ring (top a, top b, bottom b, bottom a)
        ring = [top[2 * i], top[2 * i + 1], bottom[2 * i + 1], bottom[2 * i]]
        P = np.array(V)[ring]
        mid = P.mean(axis=0)
        left = np.array([-normal[k, 1], normal[k, 0], 0.0])
        corners = [(np.sign(np.dot(q - mid, left)), np.sign(q[2] - mid[2])) for q in P]
        for j in range(1, rings[k] + 1):
            t = j / rings[k]
            half_turn = heading[k] + 0.5 * turn[k] * t  # mean heading of the arc so far
            d = np.array([np.cos(heading[k] + turn[k] * t), np.sin(heading[k] + turn[k] * t), 0.0])
            e = np.array([-d[1], d[0], 0.0])
            centre = mid + (lengths[k] - apothem) * t * np.array([np.cos(half_turn), np.sin(half_turn), 0.0])
            scale = 1.0 + (taper - 1.0) * t  # the section shrinks toward the tube's end
            crown = rise * 2 * h * 4 * t * (1.0 - t)
            new = []
            for side, up in corners:
                new.append(len(V))
                V.append(centre + scale * (side * 0.5 * w * e + [0.0, 0.0, up * h]) + [0.0, 0.0, crown * (up > 0)])
            F += [[ring[c], new[c], new[(c + 1) % 4], ring[(c + 1) % 4]] for c in range(4)]
            ring = new
    return Mesh(np.array(V), F, name=name)


def _volumes(V: np.ndarray, F: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per quad ``det[b - a, c - a, d - a]`` (zero iff planar) and its gradient ``(m, 4, 3)``."""
    a, b, c, d = (V[F[:, k]] for k in range(4))
    u, v, w = b - a, c - a, d - a
    gb, gc, gd = np.cross(v, w), np.cross(w, u), np.cross(u, v)
    return np.einsum("mi,mi->m", u, gb), np.stack([-(gb + gc + gd), gb, gc, gd], axis=1)


def flatten(mesh: Mesh, planarity: float, rounds: int = 30) -> Mesh:
    """``mesh`` (quads) moved to planar faces and then back toward itself until its worst face
    has the shared planarity measure ``planarity`` (0: as planar as the rounds reach).

    Planar: minimal-norm Gauss-Newton steps on the quads' volumes
    ``det[b - a, c - a, d - a]`` (each step the smallest vertex motion that zeroes
    their linearization), which moves every vertex about as far as its faces
    are from planar.  Back: ``V = P + s (V0 - P)`` with the one ``s`` in [0, 1]
    that leaves the worst face at ``planarity`` (planarity is nearly linear in
    ``s`` this close to planar), so the mesh is nearly planar, as a modeller's is.
    """
    import scipy.sparse as sp
    from scipy.sparse.linalg import spsolve

    from ..mesh.measures import planarity as quad_planarity

    F = mesh.F[:, :4]
    V0 = mesh.V
    m = len(F)
    rows = np.repeat(np.arange(m), 12)
    cols = (3 * F[:, :, None] + np.arange(3)).reshape(-1)
    P = V0.copy()
    for _ in range(rounds):  # Gauss-Newton on m residuals; stops on the measure
        if quad_planarity(mesh.with_vertices(P)).max() <= max(1e-3 * planarity, 1e-14):
            break
        r, g = _volumes(P, F)
        J = sp.csr_matrix((g.reshape(-1), (rows, cols)), shape=(m, 3 * len(P)))
        P = P - (J.T @ spsolve((J @ J.T).tocsc(), r)).reshape(-1, 3)
    if planarity <= 0:
        return mesh.with_vertices(P, name=mesh.name)
    if quad_planarity(mesh).max() <= planarity:
        return mesh
    lo, hi = 0.0, 1.0
    for _ in range(40):  # bisection on s: the worst face's planarity grows with s
        s = 0.5 * (lo + hi)
        if quad_planarity(mesh.with_vertices(P + s * (V0 - P))).max() > planarity:
            hi = s
        else:
            lo = s
    return mesh.with_vertices(P + lo * (V0 - P), name=mesh.name)


def tunnel(*, width: float = 4000.0, height: float = 3200.0, main_length: float = 10000.0,
           branch_length: float = 8000.0, bend_deg: float = 20.0, taper: float = 1.0, rise: float = 0.0,
           rings: int = 3, subdivisions: int = 2, planarity: float = 3e-5, noise: float = 0.0,
           seed: int = 0):
    """A glazed tunnel forking in two (a pair of pants): three open ends, valence-3 and -5 vertices.

    width : tube width at the junction (mm)
    height : tube height at the junction (mm)
    main_length : main tube, from the junction centre to its end (mm)
    branch_length : each branch, from the junction centre to its end (mm)
    bend_deg : how far each branch turns toward the main tube's direction (degrees)
    taper : section at a tube's end / section at the junction
    rise : crown rise of a tube halfway along it, fraction of the height
    rings : control rings per branch (the main tube has one more)
    subdivisions : Catmull-Clark rounds of the control mesh (2 give 784 quads, 1 give 196)
    planarity : what the modeller left: worst face planarity (shared measure; 0 = planar)
    noise : vertex noise, fraction of the mean edge length
    seed : noise seed
    """
    from .subdivision import catmull_clark

    p = dict(locals())  # the parameters as given
    del p["catmull_clark"]
    name = "tunnel"
    W, H = _pos(name, "width", width), _pos(name, "height", height)
    L, B = _pos(name, "main_length", main_length), _pos(name, "branch_length", branch_length)
    apothem = W / np.sqrt(3.0)
    for key, value in (("main_length", L), ("branch_length", B)):
        if value <= 2 * apothem:
            raise ConfigError(f"design {name}: parameter {key}={value!r}, expected more than "
                              f"{2 * apothem:g} mm (twice the junction's reach at width={W:g})")
    if not (np.isfinite(bend_deg) and abs(bend_deg) <= 45):
        raise ConfigError(f"design {name}: parameter bend_deg={bend_deg!r}, expected -45..45 degrees")
    t = _pos(name, "taper", taper)
    if t > 2:
        raise ConfigError(f"design {name}: parameter taper={taper!r}, expected a positive number up to 2")
    r = _pos(name, "rise", rise, zero=True)
    k = _int(name, "rings", rings, 1, 200)
    levels = _int(name, "subdivisions", subdivisions, 0, 4)
    flat = _pos(name, "planarity", planarity, zero=True)
    coarse = control_mesh(width=W, height=H, lengths=(L, B, B), bend_deg=float(bend_deg), taper=t, rise=r,
                          rings=(k + 1, k, k), name=name)
    fine = catmull_clark(coarse, levels)[0] if levels else coarse
    mesh = _noisy(flatten(fine, flat), _pos(name, "noise", noise, zero=True), _int(name, "seed", seed, 0, 2 ** 31))
    return Design(name, mesh, 0, "catmull_clark", "conical",
                  f"tunnel forking in two, {W / 1000:g} x {H / 1000:g} m section, {mesh.n_faces} quads", p)
