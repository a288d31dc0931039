"""The compiled nesting kernel (:mod:`fabricate.export._nest_kernel`, numba) places every rectangle where
rectpack's own packer and guillotine class do, and where the Python path does; without numba (or
switched off) :func:`fabricate.export.nesting.pack` keeps the Python path."""
import sys

import numpy as np
import pytest
from cad_fixtures import dome_structure

from fabricate.cad import PartSpec, build_parts
from fabricate.export import nesting

numba = pytest.importorskip("numba", reason="the compiled nesting kernel needs numba")


def _random(seed: int, n: int) -> tuple[np.ndarray, np.ndarray]:
    """``n`` seeded rectangles: mixed sizes, many repeated (equal areas: ties, merged sections), strips."""
    rng = np.random.default_rng(seed)
    k = n // 4
    sizes = np.concatenate([rng.integers(5, 400, (n - 3 * k, 2)), np.repeat([[100, 40], [40, 100]], k // 2, 0),
                            rng.integers(1, 60, (k, 2)) * [1, 8], rng.integers(150, 700, (k, 2))])
    sizes = sizes[rng.permutation(len(sizes))]
    return sizes[:, 0].astype(np.int64), sizes[:, 1].astype(np.int64)


@pytest.mark.parametrize("next_fit", [False, True])
@pytest.mark.parametrize("rotation", [True, False])
def test_kernel_places_hundreds_of_random_rectangles_where_rectpack_does(rotation, next_fit, monkeypatch):
    """800 seeded rectangles on sheets (scores of open bins) and on one strip (hundreds of free
    sections): the kernel's placements are rectpack's, bin, corner and turn, rectangle by rectangle
    (rectpack's own packer is the slow side: 2,000 took 2 s a case)."""
    import rectpack

    monkeypatch.setattr(nesting, "KERNEL_FROM", 0)
    assert nesting._kernel() is not None
    w, h = _random(3, 800)
    for bw, bh in ((1000, 800), (int(np.sqrt((w * h).sum()) * 1.1), int(h.sum()) + 1)):
        ours = nesting.pack(w, h, bw, bh, rotation, next_fit=next_fit)
        theirs = nesting._rectpack(w, h, bw, bh, rotation, next_fit, rectpack.GuillotineBssfSas)
        for a, b in zip(ours, theirs):
            assert np.array_equal(a, b)
        assert (ours[0] >= 0).sum() == np.sum(((w <= bw) & (h <= bh)) | (rotation & (h <= bw) & (w <= bh)))


@pytest.mark.parametrize("next_fit", [False, True])
@pytest.mark.parametrize("rotation", [True, False])
def test_kernel_and_python_path_agree(rotation, next_fit, monkeypatch):
    """The kernel and the Python path (:class:`~fabricate.export.guillotine.GuillotineBssfSas` and the bin
    skipping of :func:`~fabricate.export.nesting.pack`) on 4,000 seeded rectangles, one bin size that
    leaves a rectangle unplaced when it may not turn."""
    w, h = _random(5, 4000)
    w[17], h[17] = 1100, 90                                          # fits only turned
    runs = []
    for kernel_from in (0, 10**9):
        monkeypatch.setattr(nesting, "KERNEL_FROM", kernel_from)
        runs.append(nesting.pack(w, h, 1000, 1200, rotation, next_fit=next_fit))
    for a, b in zip(*runs):
        assert np.array_equal(a, b)
    assert (runs[0][0][17] >= 0) == rotation


def test_kernel_lays_out_a_small_dome_as_rectpack_does(monkeypatch):
    """The parts of a small dome, on a strip and on sheets (turned or not): the kernel's layouts are those
    of rectpack's own packer."""
    import rectpack

    parts = build_parts(dome_structure(n_around=8, k=4), PartSpec(glass_thickness=8.0))
    monkeypatch.setattr(nesting, "KERNEL_FROM", 0)
    for args in ((None, 10.0, None, True, ("panel", "beam"), None, "S"),
                 ((6000.0, 3210.0), 10.0, 3.0, True, ("panel", "beam"), None, "G"),
                 ((12000.0, 2500.0), 10.0, 3.0, False, ("beam",), None, "B")):
        ours, theirs = nesting._layout(parts, *args), nesting._layout(parts, *args, algo=rectpack.GuillotineBssfSas)
        assert ours.sheets == theirs.sheets and ours.size == theirs.size and len(ours.ids) > 50
        for name in ("sheet", "x", "y", "rotated", "utilisation"):
            assert np.array_equal(getattr(ours, name), getattr(theirs, name))


def test_without_numba_pack_takes_the_python_path(monkeypatch):
    import fabricate.export
    from optimize import kernels

    monkeypatch.setattr(kernels, "_LOADED", {})
    monkeypatch.setitem(sys.modules, "numba", None)  # import numba raises ImportError
    monkeypatch.delitem(sys.modules, "fabricate.export._nest_kernel", raising=False)
    monkeypatch.delattr(fabricate.export, "_nest_kernel", raising=False)
    monkeypatch.setattr(nesting, "KERNEL_FROM", 0)
    assert nesting._kernel() is None
    w, h = _random(2, 200)
    sheet, x, y, pw = nesting.pack(w, h, 1000, 800)
    assert (sheet >= 0).all()
    monkeypatch.setattr(kernels, "_LOADED", {})  # forget the failed import afterwards
    monkeypatch.setattr(kernels, "ENABLED", False)                # the optimizer's switch, CONICAL_FAB_NUMBA
    assert nesting._kernel() is None


def test_kernel_and_python_path_agree_on_small_odd_cases(monkeypatch):
    """200 small seeded cases: bins from a few mm, rectangles of the bin's size and its halves (exact fits,
    merged sections), many too large for the bin (unplaced, also amid next fit); then a rectangle of no
    width fails rectpack's assertion on both paths."""
    for seed in range(200):
        rng = np.random.default_rng(seed)
        n, bw, bh = int(rng.integers(1, 150)), int(rng.integers(5, 300)), int(rng.integers(5, 300))
        top = int(rng.integers(2, 200))
        w, h = rng.integers(1, top, n), rng.integers(1, top, n)
        if seed % 3 == 0:
            w, h = rng.choice([bw, bw // 2, bw // 3 + 1, 7], n), rng.choice([bh, bh // 2, bh // 4 + 1, 7], n)
        w, h = np.maximum(w, 1), np.maximum(h, 1)
        runs = []
        for kernel_from in (0, 10**9):
            monkeypatch.setattr(nesting, "KERNEL_FROM", kernel_from)
            runs.append(nesting.pack(w, h, bw, bh, bool(seed % 2), next_fit=seed % 4 < 2))
        for a, b in zip(*runs):
            assert np.array_equal(a, b), seed
    for kernel_from in (0, 10**9):
        monkeypatch.setattr(nesting, "KERNEL_FROM", kernel_from)
        with pytest.raises(AssertionError):
            nesting.pack(np.array([5, 0]), np.array([5, 5]), 10, 10)
