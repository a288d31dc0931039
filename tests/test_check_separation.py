"""The intersection check's broad phase (box pairs by size classes) and narrow phase (separating planes
in buckets) against brute-force all-pairs oracles, on small cases that mix tiny plates and big parts."""
from __future__ import annotations

import itertools

import manifold3d
import numpy as np
import pytest

from fabricate.export.separation import overlapping_boxes, separated
from fabricate.export.verify import Solid, intersections, solids_of

TOL = 1e-3  # mm, the CAD linear tolerance


def brute_boxes(lo, hi, pad):
    return [(i, j) for i, j in itertools.combinations(range(len(lo)), 2)
            if (lo[i] <= hi[j] + pad).all() and (lo[j] <= hi[i] + pad).all()]


def mixed_boxes(rng, n):
    """Boxes from 0.5 mm to 2 m, some of them copies moved to touch a neighbour exactly."""
    size = 10.0 ** rng.uniform(-0.3, 3.3, (n, 1)) * rng.uniform(0.02, 1.0, (n, 3))
    lo = rng.uniform(0.0, 3000.0, (n, 3))
    hi = lo + size
    for k in range(0, n - 1, 7):                      # touching: box k + 1 starts where box k ends
        lo[k + 1, 0] = hi[k, 0]
        hi[k + 1, 0] = lo[k + 1, 0] + size[k + 1, 0]
        lo[k + 1, 1:], hi[k + 1, 1:] = lo[k, 1:], lo[k, 1:] + size[k + 1, 1:]
    return lo, hi


@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("pad", [0.0, TOL, 50.0])
def test_box_pairs_equal_all_pairs(seed, pad):
    lo, hi = mixed_boxes(np.random.default_rng(seed), 300)
    got = overlapping_boxes(lo, hi, pad)
    want = brute_boxes(lo, hi, pad)
    assert len(want) > 20                              # the case has pairs to find
    assert [tuple(p) for p in got.tolist()] == want    # the same pairs, each once, sorted


def test_box_pairs_degenerate():
    assert overlapping_boxes(np.zeros((0, 3)), np.zeros((0, 3))).shape == (0, 2)
    assert overlapping_boxes(np.zeros((1, 3)), np.ones((1, 3))).shape == (0, 2)
    # equal boxes, point boxes and boxes touching at a corner only
    lo = np.array([[0, 0, 0], [0, 0, 0], [1, 1, 1], [1, 1, 1], [2, 2, 2], [5, 5, 5]], dtype=float)
    hi = np.array([[1, 1, 1], [1, 1, 1], [1, 1, 1], [2, 2, 2], [3, 3, 3], [5, 5, 5]], dtype=float)
    assert [tuple(p) for p in overlapping_boxes(lo, hi).tolist()] == brute_boxes(lo, hi, 0.0)


def box(x0, x1, rot: float = 0.0):
    """A box mesh ``(V, T)`` over ``x0 .. x1`` (mm), turned by ``rot`` radians about its centre's z axis."""
    x0, x1 = np.asarray(x0, float), np.asarray(x1, float)
    m = manifold3d.Manifold.cube(tuple(x1 - x0), center=True)
    if rot:
        m = m.rotate((0.0, 0.0, float(np.degrees(rot))))
    m = m.translate(tuple(0.5 * (x0 + x1)))
    return mesh_of(m)


def mesh_of(m):
    mesh = m.to_mesh()
    return np.asarray(mesh.vert_properties, dtype=float)[:, :3], np.asarray(mesh.tri_verts, dtype=np.int64)


def tube(centre, outer, inner, height):
    """A square tube (not convex, genus 1) standing on ``centre``."""
    m = (manifold3d.Manifold.cube((outer, outer, height), center=True)
         - manifold3d.Manifold.cube((inner, inner, height + 2.0), center=True))
    return mesh_of(m.translate((centre[0], centre[1], centre[2] + 0.5 * height)))


def oracle(objects):
    """Failing pairs by brute force: every pair's intersection volume against the check's limit."""
    S = {n: Solid(n, *vt) for n, vt in objects.items()}
    bad = set()
    for a, b in itertools.combinations(S, 2):
        vol = (S[a].manifold ^ S[b].manifold).volume()
        if vol > TOL * min(S[a].area, S[b].area):
            bad.add(frozenset((a, b)))
    return bad


def check(objects):
    r = intersections(list(solids_of(objects).values()), TOL)
    return r, {frozenset(f["pair"]) for f in r["failures"]}


def test_touching_parts_are_not_clashes():
    objects = {"A": box((0, 0, 0), (10, 10, 10)), "B": box((10, 0, 0), (20, 10, 10)),   # face to face
               "C": box((0, 10, 0), (10, 20, 10)), "D": box((10, 10, 10), (20, 20, 20))}  # edge, corner
    r, bad = check(objects)
    assert r["pass"] and not bad and r["box_pairs"] == 6 and r["failed"] == 0
    assert oracle(objects) == set()


def test_one_cubic_millimetre_overlap_is_found():
    objects = {"A": box((0, 0, 0), (10, 10, 10)), "B": box((9, 9, 9), (19, 19, 19))}
    r, bad = check(objects)
    assert not r["pass"] and bad == {frozenset("AB")}
    assert r["failures"][0]["volume_mm3"] == pytest.approx(1.0, rel=1e-6)
    assert oracle(objects) == bad


def test_mixed_sizes_against_brute_force():
    """A slab, a non-convex tube and thin plates: on the slab (touching), into it by 1 mm (clash),
    apart, turned, and inside the tube's hole (boxes overlap, the parts do not)."""
    objects = {"slab": box((0, 0, 0), (2000, 1500, 20)), "tube": tube((1000, 700, 20), 220, 200, 300)}
    rng = np.random.default_rng(3)
    want = set()
    for k in range(24):
        x, y = rng.uniform(50, 1800), rng.uniform(50, 1300)
        kind = k % 4
        z0 = {0: 20.0, 1: 19.0, 2: 25.0, 3: 20.0}[kind]        # touching, 1 mm in, apart, touching turned
        name = f"plate{k}"
        objects[name] = box((x, y, z0), (x + 5, y + 100, z0 + 5), rot=0.3 if kind == 3 else 0.0)
        if kind == 1:
            want.add(frozenset(("slab", name)))
    objects["in hole"] = box((960, 660, 100), (1040, 740, 110))     # inside the tube, touching nothing
    objects["through wall"] = box((1095, 690, 100), (1120, 710, 110))  # through the tube's wall
    want.add(frozenset(("tube", "through wall")))
    r, bad = check(objects)
    assert bad == want == oracle(objects)
    names = list(objects)
    S = solids_of(objects)
    lo = np.array([S[n].V.min(axis=0) for n in names])
    hi = np.array([S[n].V.max(axis=0) for n in names])
    assert r["box_pairs"] == len(brute_boxes(lo, hi, TOL))
    assert r["boolean_pairs"] >= 1                     # the part in the hole needs the boolean


def test_separated_equals_one_pair_at_a_time():
    """The bucketed plane test gives :meth:`Solid.separates` for every pair, whatever the part sizes."""
    objects = {"slab": box((0, 0, 0), (500, 500, 20)), "tube": tube((250, 250, 20), 120, 100, 200)}
    rng = np.random.default_rng(5)
    for k in range(30):
        x0 = rng.uniform(0, 450, 3) * np.array([1, 1, 0.2])
        objects[f"p{k}"] = box(x0, x0 + rng.uniform(2, 60, 3), rot=rng.uniform(0, 1))
    S = list(solids_of(objects).values())
    pairs = np.array([(i, j) for i in range(len(S)) for j in range(len(S)) if i != j])
    got = separated([s.support_planes for s in S], [s.V for s in S], pairs[:, 0], pairs[:, 1], TOL)
    want = [S[i].separates(S[j], TOL) for i, j in pairs.tolist()]
    assert got.tolist() == want
    assert 0 < got.sum() < len(got)                    # both outcomes occur
