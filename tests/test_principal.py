"""Principal directions by volume PCA (integral invariants) against exact ones on analytic surfaces."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import cKDTree

from optimize import ConfigError, Mesh, MeshError
from optimize.remesh import surfaces
from optimize.remesh.principal import principal_directions, principal_frames
from optimize.remesh.principal_quadric import quadric_frames


def _rotation(seed: int) -> np.ndarray:
    q, _ = np.linalg.qr(np.random.default_rng(seed).standard_normal((3, 3)))
    return q * np.sign(np.linalg.det(q))


def _probe(surf, r, count=250, seed=0, min_aniso=0.2):
    """Seeded vertices away from the boundary (> r) and from umbilics (relative anisotropy > min_aniso)."""
    m = surf.mesh
    _, _, _, k1, k2 = surf.exact()
    aniso = (k1 - k2) / np.maximum(np.abs(k1) + np.abs(k2), 1e-12)
    b = m.topology.is_boundary_vertex
    dist = cKDTree(m.V[b]).query(m.V)[0] if b.any() else np.full(m.n_vertices, np.inf)
    ok = np.nonzero((aniso > min_aniso) & (dist > r))[0]
    assert len(ok) >= count // 2, "fixture has too few usable vertices"
    return np.random.default_rng(seed).choice(ok, size=min(count, len(ok)), replace=False)


def _errors(surf, frames, at):
    d1, _, n, _, _ = surf.exact(surf.mesh.V[at])
    return surfaces.angle_error(frames.k1dir, d1, n)


CASES = {
    "ellipsoid": (lambda: surfaces.ellipsoid(level=4), 0.2),
    "torus": (lambda: surfaces.torus(), 0.3),
    "revolution": (lambda: surfaces.revolution_patch(), 0.3),
    "saddle": (lambda: surfaces.height_field(), 0.4),
}


@pytest.mark.parametrize("name", sorted(CASES))
def test_directions_agree_with_exact(name):
    make, r = CASES[name]
    surf = make()
    at = _probe(surf, r)
    fr = principal_frames(surf.mesh, None, r, side=surf.side, at=at)
    err = _errors(surf, fr, at)
    assert err.mean() < 1.5, f"{name}: mean error {err.mean():.2f} deg"
    assert np.percentile(err, 95) < 4.0, f"{name}: 95th percentile {np.percentile(err, 95):.2f} deg"
    # k2dir completes the frame
    assert np.allclose(np.cross(fr.normals, fr.k1dir), fr.k2dir)
    assert np.allclose(np.einsum("ij,ij->i", fr.k1dir, fr.normals), 0, atol=1e-12)
    # curvature estimates: sign and size right (kappa r small: a few percent)
    _, _, _, k1, k2 = surf.exact(surf.mesh.V[at])
    scale = np.abs(k1).mean() + np.abs(k2).mean()
    assert np.median(np.abs(fr.k1 - k1)) < 0.15 * scale
    assert np.median(np.abs(fr.k2 - k2)) < 0.15 * scale


def test_error_shrinks_with_radius():
    surf = surfaces.ellipsoid(level=5)
    at = _probe(surf, 0.4, count=200)
    e_big = _errors(surf, principal_frames(surf.mesh, None, 0.4, at=at), at).mean()
    e_small = _errors(surf, principal_frames(surf.mesh, None, 0.2, at=at), at).mean()
    assert e_small < 0.7 * e_big, (e_small, e_big)


def test_noise_of_one_percent_of_r_changes_little_and_less_than_a_quadric_fit():
    surf = surfaces.ellipsoid(level=4)
    r = 0.3
    at = _probe(surf, r, count=300)
    rng = np.random.default_rng(7)
    noisy = surf.mesh.with_vertices(surf.mesh.V + 0.01 * r * rng.standard_normal(surf.mesh.V.shape))
    change = {}
    for name, fn in (("pca", principal_frames), ("quadric", quadric_frames)):
        a, b = fn(surf.mesh, None, r, at=at), fn(noisy, None, r, at=at)
        change[name] = surfaces.angle_error(b.k1dir, a.k1dir, a.normals).mean()
    assert change["pca"] < 3.0, change
    assert change["pca"] < 0.75 * change["quadric"], change


def test_sphere_curvature_and_sides():
    sph = surfaces.ellipsoid(2.0, 2.0, 2.0, level=4)
    fr = principal_frames(sph.mesh, None, 0.5, at=np.arange(0, sph.mesh.n_vertices, 7))
    # the integral-invariant formula is first order: a bias O(kappa r) (about 9% at kappa r = 1/4)
    assert np.allclose(fr.k1, 0.5, rtol=0.12) and np.allclose(fr.k2, 0.5, rtol=0.12)
    assert np.abs(fr.k1 - fr.k2).max() < 0.02
    # a roof bending down is convex seen from above; from below (side up) the signs flip
    dome = surfaces.height_field((lambda x, y: -0.1 * x * x - 0.05 * y * y,
                                  lambda x, y: np.stack([-0.2 * x, -0.1 * y], 1),
                                  lambda x, y: np.broadcast_to(np.diag([-0.2, -0.1]), (len(x), 2, 2)).copy()))
    at = _probe(dome, 0.4, count=60)
    down = principal_frames(dome.mesh, None, 0.4, at=at)
    up = principal_frames(dome.mesh, None, 0.4, side=(0, 0, 1), at=at)
    assert np.all(down.k2 > 0) and np.all(up.k1 < 0)
    assert np.allclose(down.k1, -up.k2, rtol=1e-6, atol=1e-9)


def test_plane_has_zero_curvature():
    plane = surfaces.height_field((lambda x, y: 0.3 * x - 0.2 * y,
                                   lambda x, y: np.tile([0.3, -0.2], (len(x), 1)),
                                   lambda x, y: np.zeros((len(x), 2, 2))))
    at = _probe(plane, 0.4, count=50, min_aniso=-1)
    fr = principal_frames(plane.mesh, None, 0.4, at=at)
    assert np.abs(fr.k1).max() < 1e-7 / 0.4 and np.abs(fr.k2).max() < 1e-7 / 0.4


def test_invariance_under_rigid_motion_and_scale():
    surf = surfaces.torus(nu=60, nv=24)
    at = np.arange(0, surf.mesh.n_vertices, 11)
    r = 0.35
    base = principal_frames(surf.mesh, None, r, at=at)
    Q, s, t = _rotation(3), 2.5, np.array([1.0, -2.0, 0.5])
    moved = principal_frames(s * surf.mesh.V @ Q.T + t, surf.mesh.F, s * r, at=at)
    assert np.allclose(moved.k1 * s, base.k1, rtol=0.05, atol=0.02)
    turned = base.k1dir @ Q.T
    err = surfaces.angle_error(moved.k1dir, turned, base.normals @ Q.T)
    assert err.mean() < 1.0, err.mean()  # the lattice turns with the frame: quadrature differs a little
    scaled = principal_frames(s * surf.mesh.V, surf.mesh.F, s * r, at=at)
    assert np.allclose(scaled.k1dir, base.k1dir, atol=1e-7)
    assert np.allclose(scaled.k1 * s, base.k1, rtol=1e-7)


def test_quadric_fit_is_exact_on_a_quadric_and_functional_api():
    surf = surfaces.height_field()
    at = _probe(surf, 0.4, count=80)
    err = _errors(surf, quadric_frames(surf.mesh, None, 0.4, side=surf.side, at=at), at)
    assert err.max() < 0.5
    d1, d2, n = principal_directions(surf.mesh.V, surf.mesh.F, 0.4, at=at)
    assert d1.shape == d2.shape == n.shape == (len(at), 3)
    assert np.allclose(np.linalg.norm(d1, axis=1), 1)


def test_inputs_are_not_changed():
    surf = surfaces.height_field(n=(15, 12))
    V, F = surf.mesh.V.copy(), surf.mesh.F.copy()
    principal_frames(surf.mesh, None, 0.8)
    quadric_frames(surf.mesh, None, 0.8)
    assert np.array_equal(V, surf.mesh.V) and np.array_equal(F, surf.mesh.F)


def test_bad_input_raises_with_the_facts():
    surf = surfaces.height_field(n=(9, 7))
    with pytest.raises(ConfigError, match="radius"):
        principal_frames(surf.mesh, None, -1.0)
    with pytest.raises(ConfigError, match="side vector"):
        principal_frames(surf.mesh, None, 0.5, side=(1, 0, 0))
    with pytest.raises(ConfigError, match="side"):
        principal_frames(surf.mesh, None, 0.5, side=(0, 0, 0))
    quad = Mesh(np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0.0]]), [[0, 1, 2, 3]])
    with pytest.raises(MeshError, match="triangle"):
        principal_frames(quad, None, 0.5)
    with pytest.raises(ConfigError, match="out of range"):
        principal_frames(surf.mesh, None, 0.5, at=[10_000])
    with pytest.raises(ConfigError, match="at least 6"):
        quadric_frames(surf.mesh, None, 1e-3)
